#include "sim/tool_policy.hpp"

#include "core/stopwatch.hpp"
#include "io/mesh.hpp"

#include <stdexcept>

namespace vox::sim {

contact::ToolShape make_tool_shape(const io::ToolSpec& t)
{
    switch (t.shape) {
    case io::ToolShape::blade:
        return contact::ToolShape::box(t.size_mm);
    case io::ToolShape::scalpel:
        return contact::ToolShape::scalpel(t.size_mm); // the scene reader gives scalpels their default size
    case io::ToolShape::sphere:
        return contact::ToolShape::sphere(t.radius_mm);
    case io::ToolShape::cylinder:
        return contact::ToolShape::cylinder(t.radius_mm, t.length_mm);
    case io::ToolShape::mesh: {
        const io::TriangleMesh m = io::read_mesh(t.mesh.string());
        return contact::ToolShape::from_mesh({m.vertices, m.triangles});
    }
    }
    throw std::logic_error("make_tool_shape: unknown tool shape");
}

ToolPolicy::ToolPolicy(const io::Scene& scene)
    : m_scene(scene), m_last_pose(scene.tools.size()), m_episode_cut(scene.tools.size(), false), m_driven(scene.tools.size(), false),
      m_driven_pose(scene.tools.size())
{
    for (const io::ToolSpec& t : scene.tools) m_shapes.push_back(make_tool_shape(t));
}

void ToolPolicy::drive(std::size_t tool, const Eigen::Vector3d& position_mm, const Eigen::Quaterniond& orientation)
{
    if (!m_driven.at(tool)) m_last_pose[tool] = {}; // the device's first pose is no move from the script's
    m_driven[tool] = true;
    m_driven_pose[tool].position = position_mm;
    m_driven_pose[tool].orientation = orientation;
}

void ToolPolicy::release(std::size_t tool)
{
    m_driven.at(tool) = false;
    m_last_pose[tool] = {};
}

void ToolPolicy::reset()
{
    for (std::size_t k = 0; k < m_last_pose.size(); ++k) {
        m_last_pose[k] = {};
        m_episode_cut[k] = false;
    }
}

ToolsFrame ToolPolicy::frame(Method& method, double t_s, double dt_s)
{
    ToolsFrame out;
    out.tools.resize(m_scene.tools.size());
    method.begin_tools(m_scene.tools.size());
    Stopwatch clock;
    for (std::size_t k = 0; k < m_scene.tools.size(); ++k) {
        const io::ToolSpec& spec = m_scene.tools[k];
        io::ToolPose from = io::tool_pose(m_scene, k, t_s - dt_s), to = io::tool_pose(m_scene, k, t_s);
        if (m_driven[k]) { // a device moves this tool: from where it was at the last frame
            to.placed = true;
            to.position_mm = m_driven_pose[k].position;
            to.orientation = m_driven_pose[k].orientation;
            from = to;
            if (m_last_pose[k].shape) {
                from.position_mm = m_last_pose[k].position;
                from.orientation = m_last_pose[k].orientation;
            }
        }
        ToolFrame& t = out.tools[k];
        t.placed = to.placed;
        if (!to.placed) {
            m_last_pose[k] = {}; // back later: from wherever it reappears
            m_episode_cut[k] = false;
            method.lift(k);
            continue;
        }
        t.position_mm = to.position_mm;
        const contact::PlacedShape placed{&m_shapes[k], to.position_mm, to.orientation};
        // The penalty integrated over the tool's move since the last frame (continuous penalty):
        // a tool arriving between two frames pushes for the part of the frame it was there.
        const bool moved_on = m_last_pose[k].shape == placed.shape;
        const contact::ContactResult& c = method.touch(k, spec, placed, moved_on ? &m_last_pose[k] : nullptr);
        m_last_pose[k] = placed;
        t.force_n = c.force_on_tool_n;
        t.torque_n_mm = c.torque_on_tool_n_mm;
        t.pressure_pa = c.pressure_pa;
        t.contact_area_mm2 = c.area_mm2;
        CutOrder order;
        order.touching = !c.points.empty();
        const bool breaks_in = c.inner_reaches_surface() && c.pressure_pa >= spec.cut_pressure_pa;
        out.collision_ms += clock.lap();
        if (spec.action == io::ToolAction::cut) {
            if (!order.touching) m_episode_cut[k] = false; // let go: the next touch marks a new cut
            order.marking = spec.two_phase && order.touching && !m_episode_cut[k];
            order.cut = breaks_in && (!spec.two_phase || order.marking);
            const CutFigures cut = method.follow(k, spec, from, placed, order);
            if (cut.changed()) {
                t.cut = true;
                if (spec.two_phase) m_episode_cut[k] = true; // the object moves again
            }
            if (order.marking && !m_episode_cut[k]) out.hold_object = true;
            out.cut += cut;
            out.propagation_ms += clock.lap() - cut.grid_update_ms - cut.remesh_ms - cut.fem_update_ms;
        }
        if (spec.action == io::ToolAction::wet) method.wet(k, spec.wet_rate_per_s * dt_s);
        if (spec.action == io::ToolAction::drill && order.touching) {
            // Removal rate = rate constant x pressing force x revolutions per second (Agus et
            // al. 2003; Morris et al. 2006 remove bone voxels at a force- and speed-driven rate).
            const double volume_mm3 = spec.drill_rate_mm3_per_n_rev * c.force_on_tool_n.norm() * spec.burr_speed_rpm / 60.0 * dt_s;
            const CutFigures cut = method.drill(k, spec, placed, volume_mm3);
            if (cut.changed()) t.cut = true;
            out.cut += cut;
            out.propagation_ms += clock.lap() - cut.grid_update_ms - cut.remesh_ms - cut.fem_update_ms;
        }
    }
    method.end_tools();
    out.collision_ms += clock.lap();
    return out;
}

} // namespace vox::sim
