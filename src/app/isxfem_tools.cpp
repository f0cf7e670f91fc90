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
    }
}

IsxfemTools::IsxfemTools(const io::Scene& scene)
    : m_scene(scene), m_last_pose(scene.tools.size()), m_done(scene.tools.size(), false), m_driven(scene.tools.size())
{
    check_isxfem_tools(scene);
    for (const io::ToolSpec& t : scene.tools) {
        m_shapes.push_back(make_tool_shape(t));
        m_strokes.emplace_back();
        if (t.action == io::ToolAction::cut) m_strokes.back().emplace(t);
    }
}

void IsxfemTools::drive(std::size_t tool, const Eigen::Vector3d& position_mm, const Eigen::Quaterniond& orientation)
{
    io::ToolPose pose;
    pose.placed = true;
    pose.position_mm = position_mm;
    pose.orientation = orientation;
    m_driven.at(tool) = pose;
}

IsxfemToolFrame IsxfemTools::frame(IsxfemSimulation& sim, int frame, double dt)
{
    IsxfemToolFrame out;
    out.tools.resize(m_scene.tools.size());
    std::vector<isxfem::PointLoad> loads;
    std::vector<std::size_t> cuts_known; // per load: how many cuts of its tetrahedron its region knew
    for (std::size_t k = 0; k < m_scene.tools.size(); ++k) {
        const io::ToolSpec& spec = m_scene.tools[k];
        io::ToolPose from = io::tool_pose(m_scene, k, (frame - 1) * dt), to = io::tool_pose(m_scene, k, frame * dt);
        if (m_driven[k]) { // a device moves this tool: from where it was at the last frame
            from = to = *m_driven[k];
            if (m_last_pose[k].shape) {
                from.position_mm = m_last_pose[k].position;
                from.orientation = m_last_pose[k].orientation;
            }
        }
        ToolFrame& t = out.tools[k];
        t.placed = to.placed;
        if (!to.placed) {
            m_last_pose[k] = {}; // back later: from wherever it reappears
            if (m_strokes[k]) m_strokes[k]->end();
            m_done[k] = false;
            continue;
        }
        t.position_mm = to.position_mm;
        // The penalty integrated over the tool's move since the last frame.
        const contact::PlacedShape placed{&m_shapes[k], to.position_mm, to.orientation};
        const IsxfemSimulation::Touch touch =
            sim.touch(placed, {spec.push_margin_mm, spec.contact_stiffness_n_per_mm}, m_last_pose[k].shape ? &m_last_pose[k] : nullptr,
                      m_strokes[k] ? spec.size_mm.y() : 0.0); // a blade's thickness
        m_last_pose[k] = placed;
        loads.insert(loads.end(), touch.loads.begin(), touch.loads.end());
        for (const isxfem::PointLoad& l : touch.loads) cuts_known.push_back(sim.model().elements()[l.tet].cuts.size());
        t.force_n = touch.contact.force_on_tool_n;
        t.torque_n_mm = touch.contact.torque_on_tool_n_mm;
        t.pressure_pa = touch.contact.pressure_pa;
        t.contact_area_mm2 = touch.contact.area_mm2;
        if (!m_strokes[k]) continue;
        BladeStroke& stroke = *m_strokes[k];
        if (touch.contact.points.empty()) { // let go (or not yet touching): the next touch starts anew
            stroke.end();
            m_done[k] = false;
            continue;
        }
        const bool breaks_in = touch.contact.inner_reaches_surface() && touch.contact.pressure_pa >= spec.cut_pressure_pa;
        isxfem::CutReport r;
        if (spec.two_phase && !m_done[k]) {
            // Marking: the object is held (so the material around the blade has not moved since the
            // marking began) and the blade's path counts from the first touch.
            r = stroke.advance(sim, from, to, sim.mean_displacement_mm(placed.world_bounds(spec.push_margin_mm)), breaks_in);
            m_done[k] = breaks_in;
            out.hold_object = out.hold_object || !breaks_in;
        } else {
            m_done[k] = m_done[k] || breaks_in;
            if (!m_done[k]) continue;
            r = stroke.advance(sim, from, to, sim.mean_displacement_mm(placed.world_bounds(spec.push_margin_mm)), true);
        }
        out.cut.cut_tets += r.cut_tets;
        out.cut.new_blocks += r.new_blocks;
        out.cut.partial_tets += r.partial_tets;
        out.cut.already_cut += r.already_cut;
        out.cut.beside_earlier += r.beside_earlier;
        out.cut.recut_tets += r.recut_tets;
        out.cut.crossed_tets += r.crossed_tets;
        t.cut = r.cut_tets > 0;
    }
    // A cut this frame may have cut a loaded point's tetrahedron: the point acts on its own side of
    // the new cut, and keeps its sides of the earlier ones (cuts are appended; a point on an earlier
    // crack's face knows its side, which rounding at the plane would not).
    if (out.cut.cut_tets > 0)
        for (std::size_t i = 0; i < loads.size(); ++i) {
            const unsigned known = (1u << cuts_known[i]) - 1u;
            const unsigned now = static_cast<unsigned>(sim.side_of(loads[i].tet, loads[i].bary));
            loads[i].side = static_cast<int>((static_cast<unsigned>(loads[i].side) & known) | (now & ~known));
        }
    sim.solver().set_point_loads(std::move(loads));
    return out;
}

} // namespace vox::app
