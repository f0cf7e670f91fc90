#include "app/tool_session.hpp"

#include "core/stopwatch.hpp"
#include "cut/surface_contact.hpp"
#include "cut/voxel_cut.hpp"
#include "io/mesh.hpp"
#include "io/tool_script.hpp"

#include <algorithm>
#include <stdexcept>
#include <utility>

namespace vox::app {

contact::ToolShape make_tool_shape(const io::ToolSpec& t)
{
    switch (t.shape) {
    case io::ToolShape::blade:
        return contact::ToolShape::box(t.size_mm);
    case io::ToolShape::scalpel:
        return contact::ToolShape::scalpel(t.size_mm); // the scene reader gives scalpels their default size
    case io::ToolShape::sphere:
        return contact::ToolShape::sphere(t.radius_mm);
    case io::ToolShape::mesh: {
        const io::TriangleMesh m = io::read_mesh(t.mesh.string());
        return contact::ToolShape::from_mesh({m.vertices, m.triangles});
    }
    }
    throw std::logic_error("make_tool_shape: unknown tool shape");
}

ToolSession::ToolSession(const io::Scene& scene)
    : m_scene(scene), m_previous_section(scene.tools.size()), m_marked_from(scene.tools.size()),
      m_episode_cut(scene.tools.size(), false), m_driven(scene.tools.size(), false), m_driven_pose(scene.tools.size()),
      m_last_pose(scene.tools.size())
{
    for (const io::ToolSpec& t : scene.tools) m_shapes.push_back(make_tool_shape(t));
}

void ToolSession::drive(std::size_t tool, const Eigen::Vector3d& position_mm, const Eigen::Quaterniond& orientation)
{
    if (!m_driven.at(tool)) m_last_pose[tool] = {}; // the device's first pose is no move from the script's
    m_driven[tool] = true;
    m_driven_pose[tool].position = position_mm;
    m_driven_pose[tool].orientation = orientation;
}

ToolFrameStats ToolSession::frame(SceneSimulation& sim, grid::BranchedGrid& grid, double t_s, double dt_s)
{
    ToolFrameStats stats;
    stats.tools.resize(m_scene.tools.size());
    std::vector<contact::PlacedShape> placed(m_scene.tools.size());
    std::vector<cut::SurfaceContact> touch(m_scene.tools.size());
    std::vector<bool> fresh(m_scene.tools.size(), false); // touch[k] is up to date with the model
    Stopwatch clock;
    for (std::size_t k = 0; k < m_scene.tools.size(); ++k) {
        const io::ToolSpec& spec = m_scene.tools[k];
        io::ToolPose pose = io::tool_pose(m_scene, k, t_s);
        if (m_driven[k]) { // a device moves this tool
            pose.placed = true;
            pose.position_mm = m_driven_pose[k].position;
            pose.orientation = m_driven_pose[k].orientation;
        }
        ToolFrame& out = stats.tools[k];
        out.placed = pose.placed;
        if (!pose.placed) {
            m_last_pose[k] = {}; // back later: from wherever it reappears
            continue;
        }
        out.position_mm = pose.position_mm;
        placed[k] = {&m_shapes[k], pose.position_mm, pose.orientation};
        const contact::ContactParameters parameters{spec.push_margin_mm, spec.contact_stiffness_n_per_mm};
        // The penalty integrated over the tool's move since the last frame (continuous penalty):
        // a tool arriving between two frames pushes for the part of the frame it was there.
        const bool moved_on = m_last_pose[k].shape == placed[k].shape;
        touch[k] = cut::touch_surface(sim.surface(), sim.solver().positions(), placed[k], parameters, moved_on ? &m_last_pose[k] : nullptr);
        m_last_pose[k] = placed[k];
        fresh[k] = true;
        stats.collision_ms += clock.lap();
        const contact::ContactResult& c = touch[k].contact;
        // A separating tool's section, carried back to rest space (cut/voxel_cut.hpp): each frame
        // sweeps from the previous frame's section to this one.
        std::vector<Eigen::Vector3d> rest_section;
        if (spec.action == io::ToolAction::cut && spec.cut_mode == io::CutMode::separate) {
            rest_section = cut::section_polygon(m_shapes[k], 0.0, placed[k]);
            Eigen::AlignedBox3d box;
            box.setEmpty();
            for (const Eigen::Vector3d& p : rest_section) box.extend(p);
            const Eigen::Vector3d moved = cut::mean_displacement_mm(sim.surface(), sim.solver().positions(), box);
            for (Eigen::Vector3d& p : rest_section) p -= moved;
        }
        std::vector<Eigen::Vector3d> previous = std::exchange(m_previous_section[k], rest_section);
        // Two-phase cutting: from the first touch the object is held and the tool marks its cut;
        // the whole marked path is cut at once when the condition is met.
        const bool two_phase = spec.action == io::ToolAction::cut && spec.two_phase;
        if (two_phase) {
            if (c.points.empty()) { // let go: the next touch marks a new cut
                m_marked_from[k].clear();
                m_episode_cut[k] = false;
            } else if (!m_episode_cut[k] && !rest_section.empty()) {
                if (m_marked_from[k].empty()) m_marked_from[k] = rest_section; // the marking starts here
                previous = m_marked_from[k];                                   // and is cut whole
            }
        }
        // Cutting happens only where the inner shape reaches the material and the contact
        // pressure is at or above the threshold.
        const bool marking = two_phase && !c.points.empty() && !m_episode_cut[k];
        if (spec.action == io::ToolAction::cut && (!two_phase || marking) && c.inner_reaches_surface() &&
            c.pressure_pa >= spec.cut_pressure_pa) {
            std::vector<grid::Coord> removed;
            std::vector<std::pair<grid::Coord, int>> faces;
            if (spec.cut_mode == io::CutMode::remove) {
                for (std::uint32_t v : cut::voxels_inside(sim.surface(), sim.solver().positions(), placed[k], touch[k].vertices))
                    removed.push_back(grid.voxels().coord(v));
            } else {
                faces = cut::faces_crossed(grid.voxels(), cut::sweep_polygons(previous.empty() ? rest_section : previous, rest_section,
                                                                               placed[k].orientation * Eigen::Vector3d::UnitY()));
            }
            stats.propagation_ms += clock.lap();
            if (!removed.empty() || !faces.empty()) {
                if (m_cut_log) m_cut_log->push_back({removed, faces});
                const CutTimings t = sim.apply_cut(grid, removed, faces);
                stats.grid_update_ms += t.grid_update_ms;
                stats.remesh_ms += t.remesh_ms;
                stats.fem_update_ms += t.fem_update_ms;
                stats.removed_voxels += removed.size();
                stats.separated_faces += faces.size();
                std::unordered_set<std::uint32_t> sides;
                for (const auto& [coord, axis] : faces)
                    for (const grid::Coord& side : {coord, grid::Coord(coord + grid::Coord::Unit(axis))}) {
                        const std::uint32_t v = grid.voxels().find(side);
                        sides.insert(v);
                        m_separated.insert(v);
                    }
                stats.separated_voxels += sides.size();
                out.cut = true;
                if (two_phase) m_episode_cut[k] = true; // the simulation resumes
                std::fill(fresh.begin(), fresh.end(), false); // node numbers changed: contacts are carried over
                clock.lap();
            }
        }
        if (marking && !m_episode_cut[k]) stats.hold_object = true;
        if (spec.action == io::ToolAction::wet)
            for (std::uint32_t e : touch[k].elements)
                sim.solver().set_water(e, sim.solver().water(e) + spec.wet_rate_per_s * dt_s);
    }
    // The forces for the next step, on the model as it now is.
    std::vector<fem::NodeContact> nodes;
    for (std::size_t k = 0; k < m_scene.tools.size(); ++k) {
        if (!stats.tools[k].placed) continue;
        if (!fresh[k]) touch[k].nodes = cut::node_contacts(sim.surface(), touch[k]); // onto the rebuilt model's nodes
        cut::merge_node_contacts(nodes, touch[k].nodes);
        ToolFrame& out = stats.tools[k];
        out.force_n = touch[k].contact.force_on_tool_n;
        out.torque_n_mm = touch[k].contact.torque_on_tool_n_mm;
        out.pressure_pa = touch[k].contact.pressure_pa;
        out.contact_area_mm2 = touch[k].contact.area_mm2;
    }
    sim.solver().set_contact(std::move(nodes));
    stats.collision_ms += clock.lap();
    return stats;
}

} // namespace vox::app
