#include "sim/tool_policy.hpp"

#include "core/stopwatch.hpp"
#include "io/mesh.hpp"

#include <algorithm>
#include <stdexcept>

namespace vox::sim {
namespace {

/// Surface points the neighbourhood of a tool's move over one frame may hold.
constexpr std::size_t k_near_points = 50000;

contact::ContactParameters contact_parameters(const io::ToolSpec& spec)
{
    return {spec.push_margin_mm, spec.contact_stiffness_n_per_mm};
}

} // namespace

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
      m_driven_pose(scene.tools.size()), m_driven_driver(scene.tools.size(), Eigen::Vector3d::Zero()),
      m_driven_coupling(scene.tools.size(), 0.0), m_passing(scene.tools.size(), false), m_armed(scene.tools.size(), true), m_movers(scene.tools.size())
{
    m_shapes.reserve(scene.tools.size()); // placed shapes point at them
    for (const io::ToolSpec& t : scene.tools) m_shapes.push_back(make_tool_shape(t));
    for (std::size_t k = 0; k < scene.tools.size(); ++k) m_near.emplace_back(k_near_points);
}

void ToolPolicy::drive(std::size_t tool, const Eigen::Vector3d& position_mm, const Eigen::Quaterniond& orientation, const Eigen::Vector3d& driver_mm,
                       double coupling_n_per_mm)
{
    if (!m_driven.at(tool)) m_last_pose[tool] = {}; // the device's first pose is no move from the script's
    m_driven[tool] = true;
    m_driven_pose[tool].position = position_mm;
    m_driven_pose[tool].orientation = orientation;
    m_driven_driver[tool] = driver_mm;
    m_driven_coupling[tool] = coupling_n_per_mm;
}

void ToolPolicy::release(std::size_t tool)
{
    m_driven.at(tool) = false;
    m_last_pose[tool] = {};
    m_passing[tool] = false;
}

void ToolPolicy::reset()
{
    for (std::size_t k = 0; k < m_last_pose.size(); ++k) {
        m_last_pose[k] = {};
        m_episode_cut[k] = false;
        m_passing[k] = false;
    }
}

contact::ProxyMover& ToolPolicy::mover(std::size_t tool, const io::ToolSpec& spec)
{
    const contact::ContactParameters parameters = contact_parameters(spec);
    std::unique_ptr<contact::ProxyMover>& m = m_movers[tool];
    // The viewer's keys may change a tool's margin or stiffness between frames.
    if (!m || m->contact().margin_mm != parameters.margin_mm || m->contact().stiffness_n_per_mm != parameters.stiffness_n_per_mm)
        m = std::make_unique<contact::ProxyMover>(m_shapes[tool], parameters, k_near_points);
    return *m;
}

ToolPolicy::Held ToolPolicy::hold(std::size_t tool, Method& method, const io::ToolSpec& spec, contact::PlacedShape& proxy,
                                   const Eigen::Vector3d& driver, double coupling_n_per_mm, bool moved_on)
{
    contact::ProxyMover& m = mover(tool, spec);
    const bool scripted = !m_driven[tool];
    if (scripted && moved_on) proxy.position = m_last_pose[tool].position; // from where it was; it turns with its driver
    // The surface the proxy may meet on its way to the driver.
    contact::PlacedShape at_driver = proxy;
    at_driver.position = driver;
    const double reach = spec.push_margin_mm + m.bound_mm();
    Eigen::AlignedBox3d box = proxy.world_bounds(reach);
    box.extend(at_driver.world_bounds(reach));
    contact::SurfacePoints& near = m_near[tool];
    method.sample_pressed_surface(box, spec, near); // indexed
    if (near.count == 0) {
        if (scripted) proxy.position = driver; // nothing in the way
        return {};
    }
    const contact::ContactTotals c = scripted ? m.settle(proxy, driver, coupling_n_per_mm, near) : contact::penalty_totals(proxy, m.contact(), near);
    Held out;
    out.load_scale = contact::load_scale(coupling_n_per_mm * (driver - proxy.position), c.force_on_tool_n,
                                         contact::deepest_point_mm(proxy, spec.push_margin_mm, near), m.bound_mm());
    out.breaks_in = c.inner_reaches_surface && out.load_scale * c.pressure_pa >= spec.cut_pressure_pa;
    return out;
}

ToolsFrame ToolPolicy::frame(Method& method, double t_s, double dt_s)
{
    ToolsFrame out;
    out.tools.resize(m_scene.tools.size());
    method.begin_tools(m_scene.tools.size());
    Stopwatch clock;
    for (std::size_t k = 0; k < m_scene.tools.size(); ++k) {
        const io::ToolSpec& spec = m_scene.tools[k];
        const io::ToolAction action = m_armed[k] ? spec.action : io::ToolAction::push; // a device's button may hold it back
        io::ToolPose from = io::tool_pose(m_scene, k, t_s - dt_s), to = io::tool_pose(m_scene, k, t_s);
        if (m_driven[k]) { // a device moves this tool: from where it was at the last frame
            to.placed = true;
            to.position_mm = m_driven_pose[k].position;
            to.orientation = m_driven_pose[k].orientation;
            from = to;
        }
        ToolFrame& t = out.tools[k];
        t.placed = to.placed;
        if (!to.placed) {
            m_last_pose[k] = {}; // back later: from wherever it reappears
            m_episode_cut[k] = false;
            m_passing[k] = false;
            method.lift(k);
            continue;
        }
        contact::PlacedShape placed{&m_shapes[k], to.position_mm, to.orientation};
        const bool moved_on = m_last_pose[k].shape == placed.shape;
        if (moved_on) { // the stroke goes on from where the tool (its proxy) was
            from.position_mm = m_last_pose[k].position;
            from.orientation = m_last_pose[k].orientation;
        }
        // The driver, and the proxy held at the surface of what the tool does not cut (a tool
        // cutting through passes: it goes where its driver is).
        t.driver_mm = m_driven[k] ? m_driven_driver[k] : to.position_mm;
        const double coupling = m_driven[k] ? m_driven_coupling[k] : spec.coupling_stiffness_n_per_mm.value_or(io::k_script_coupling_n_per_mm);
        if (!m_passing[k]) {
            const Held held = hold(k, method, spec, placed, t.driver_mm, coupling, moved_on);
            t.load_scale = held.load_scale;
            if (action == io::ToolAction::cut && held.breaks_in) { // the material gives way: the blade cuts on to its driver
                placed.position = t.driver_mm;
                t.load_scale = 1.0;
            }
        }
        t.position_mm = placed.position;
        t.coupling_force_n = coupling * (t.driver_mm - placed.position);
        // The penalty integrated over the tool's move since the last frame (continuous penalty):
        // a tool arriving between two frames pushes for the part of the frame it was there;
        // scaled to carry the driver's pull where the material holds the proxy.
        io::ToolSpec scaled;
        const io::ToolSpec* pressing = &spec;
        if (t.load_scale > 1.0) {
            scaled = spec;
            scaled.contact_stiffness_n_per_mm *= t.load_scale;
            pressing = &scaled;
        }
        const contact::ContactResult& c = method.touch(k, *pressing, placed, moved_on ? &m_last_pose[k] : nullptr);
        m_last_pose[k] = placed;
        t.force_n = c.force_on_tool_n;
        t.torque_n_mm = c.torque_on_tool_n_mm;
        t.pressure_pa = c.pressure_pa;
        t.contact_area_mm2 = c.area_mm2;
        CutOrder order;
        order.touching = !c.points.empty();
        const bool breaks_in = c.inner_reaches_surface() && c.pressure_pa >= spec.cut_pressure_pa;
        out.collision_ms += clock.lap();
        if (action == io::ToolAction::cut) {
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
        // A cut episode: from its first cut until the tool leaves the material, the blade goes where
        // its driver is (in its slit, along its cut) and cuts wherever the pressure breaks in.
        m_passing[k] = action == io::ToolAction::cut && (t.cut || (m_passing[k] && order.touching));
        if (action == io::ToolAction::wet) method.wet(k, spec.wet_rate_per_s * dt_s);
        if (action == io::ToolAction::drill && order.touching) {
            // Removal rate = rate constant x pressing force x revolutions per second (Agus et
            // al. 2003; Morris et al. 2006 remove bone voxels at a force- and speed-driven rate).
            // The pressing force is the driver's pull where the bone holds the burr (however
            // little of it the contact's points carry where they touch), unclamped.
            const double pressing_n = std::max(c.force_on_tool_n.norm(), t.coupling_force_n.norm());
            const double volume_mm3 = spec.drill_rate_mm3_per_n_rev * pressing_n * spec.burr_speed_rpm / 60.0 * dt_s;
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
