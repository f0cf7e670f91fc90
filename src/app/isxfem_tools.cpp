#include "app/isxfem_tools.hpp"

#include "io/tool_script.hpp"

namespace vox::app {

void check_isxfem_tools(const io::Scene& scene)
{
    for (std::size_t k = 0; k < scene.tools.size(); ++k) {
        const io::ToolSpec& t = scene.tools[k];
        const std::string where = "tools[" + std::to_string(k) + "]";
        if (t.action == io::ToolAction::wet)
            throw scene.error(where, "\"" + t.name + "\": \"isxfem\" does not wet yet; wetting tools need \"type\": \"dbg\"");
        if (t.action == io::ToolAction::cut && t.shape != io::ToolShape::blade && t.shape != io::ToolShape::scalpel)
            throw scene.error(where, "\"" + t.name + "\": \"isxfem\" cuts with blades and scalpels only so far; other cutting shapes need \"type\": \"dbg\"");
        if (t.two_phase) throw scene.error(where + ".two_phase", "\"isxfem\" has no two-phase cutting yet");
    }
}

IsxfemTools::IsxfemTools(const io::Scene& scene) : m_scene(scene), m_last_pose(scene.tools.size())
{
    check_isxfem_tools(scene);
    for (const io::ToolSpec& t : scene.tools) {
        m_shapes.push_back(make_tool_shape(t));
        m_strokes.emplace_back();
        if (t.action == io::ToolAction::cut) m_strokes.back().emplace(t);
    }
}

IsxfemToolFrame IsxfemTools::frame(IsxfemSimulation& sim, int frame, double dt)
{
    IsxfemToolFrame out;
    out.tools.resize(m_scene.tools.size());
    std::vector<isxfem::PointLoad> loads;
    for (std::size_t k = 0; k < m_scene.tools.size(); ++k) {
        const io::ToolSpec& spec = m_scene.tools[k];
        const io::ToolPose from = io::tool_pose(m_scene, k, (frame - 1) * dt), to = io::tool_pose(m_scene, k, frame * dt);
        ToolFrame& t = out.tools[k];
        t.placed = to.placed;
        if (!to.placed) {
            m_last_pose[k] = {}; // back later: from wherever it reappears
            if (m_strokes[k]) m_strokes[k]->end();
            continue;
        }
        t.position_mm = to.position_mm;
        // The penalty integrated over the tool's move since the last frame.
        const contact::PlacedShape placed{&m_shapes[k], to.position_mm, to.orientation};
        const IsxfemSimulation::Touch touch =
            sim.touch(placed, {spec.push_margin_mm, spec.contact_stiffness_n_per_mm}, m_last_pose[k].shape ? &m_last_pose[k] : nullptr);
        m_last_pose[k] = placed;
        loads.insert(loads.end(), touch.loads.begin(), touch.loads.end());
        t.force_n = touch.contact.force_on_tool_n;
        t.torque_n_mm = touch.contact.torque_on_tool_n_mm;
        t.pressure_pa = touch.contact.pressure_pa;
        t.contact_area_mm2 = touch.contact.area_mm2;
        if (!m_strokes[k]) continue;
        BladeStroke& stroke = *m_strokes[k];
        if (stroke.cutting() && touch.contact.points.empty()) { // let go: the next touch starts a new stroke
            stroke.end();
            continue;
        }
        const bool breaks_in = touch.contact.inner_reaches_surface() && touch.contact.pressure_pa >= spec.cut_pressure_pa;
        const Eigen::Vector3d moved = stroke.cutting() || breaks_in ? sim.mean_displacement_mm(placed.world_bounds(spec.push_margin_mm))
                                                                      : Eigen::Vector3d::Zero();
        const isxfem::CutReport r = stroke.advance(sim, from, to, breaks_in, moved);
        out.cut.cut_tets += r.cut_tets;
        out.cut.new_blocks += r.new_blocks;
        out.cut.partial_tets += r.partial_tets;
        out.cut.already_cut += r.already_cut;
        t.cut = r.cut_tets > 0;
    }
    sim.solver().set_point_loads(std::move(loads));
    return out;
}

} // namespace vox::app
