#include "sim/dbg_method.hpp"

#include "sim/dbg_fem_mesh.hpp"

#include "core/error.hpp"
#include "core/log.hpp"
#include "core/stopwatch.hpp"
#include "cut/piece_contact.hpp"
#include "cut/pieces.hpp"
#include "cut/voxel_cut.hpp"
#include "shape/shape_matching.hpp"

#include <algorithm>
#include <cstdint>
#include <iterator>
#include <cmath>
#include <cstdio>
#include <limits>
#include <utility>

namespace vox::sim {
namespace {

struct DbgCheckpoint final : Checkpoint {
    std::size_t cuts = 0;
    int level = 1; ///< a run may have moved since (move_to_level): restoring goes back to it
    io::PreconditionerChoice preconditioner = io::PreconditionerChoice::automatic;
    std::vector<Eigen::Vector3d> positions, velocities;
    std::vector<double> water;
    std::vector<Eigen::Matrix3d> plastic;
    std::unordered_set<std::uint32_t> separated;
    RegionCells region; ///< two levels: the fine region the state is on
};

} // namespace

DbgMethod::DbgMethod(const io::Scene& scene, std::shared_ptr<const grid::LabelGrid> labels, int level, int grid_levels)
    : DbgMethod(scene, labels, std::make_unique<grid::BranchedGrid>(build_scene_grid(scene, *labels, std::max({grid_levels, level, 1}))), level)
{
}

DbgMethod::DbgMethod(const io::Scene& scene, std::shared_ptr<const grid::LabelGrid> labels, std::unique_ptr<grid::BranchedGrid> grid, int level)
    : m_scene(scene), m_labels(std::move(labels)), m_level(level), m_grid_levels(grid->max_level()), m_grid(std::move(grid))
{
    m_obstacles = make_obstacles(m_scene);
    m_anchors.resize(m_obstacles.size());
    m_sim = std::make_unique<DbgSimulation>(m_scene, *m_grid, m_level);
    if (m_sim->held_piece_count() > 0)
        log::info("{}: {} piece(s) held by no constraint stay where they are (object.unheld_pieces \"hold\"; "
                  "\"fall\" frees them, \"leave_out\" drops them)", m_scene.source, m_sim->held_piece_count());
    if (m_sim->rigid_element_count() > 0 || m_sim->rigid_body_count() > 0)
        log::info("{}: {} element(s) hold rigid material; {} piece(s) move as rigid bodies", m_scene.source,
                  m_sim->rigid_element_count(), m_sim->rigid_body_count());
    for (const surface::SurfaceVertex& v : m_sim->surface().embedded().vertices())
        if (v.users) m_uncut.insert(v.key);
}

DbgMethod::~DbgMethod() = default;

std::string DbgMethod::linear_solver() const
{
    return m_sim->solver().fallback_note().empty() ? m_sim->linear_solver() : m_sim->solver().fallback_note();
}

std::map<int, std::size_t> DbgMethod::elements_per_level() const
{
    std::map<int, std::size_t> out;
    for (const fem::HexElement& el : m_sim->model().elements()) ++out[el.level];
    return out;
}

std::string DbgMethod::description() const
{
    char text[256];
    const fem::HexModel& model = m_sim->model();
    if (model.mixed()) {
        std::size_t fine = 0;
        for (const fem::HexElement& el : model.elements()) fine += el.level == model.level() ? 1 : 0;
        std::snprintf(text, sizeof text, "branched grid, level %d within %g mm of the tools (%zu elements) and %d elsewhere (%zu), %zu degrees of freedom",
                      model.level(), m_scene.object.mixed_levels->fine_radius_mm, fine, model.coarse_level(), element_count() - fine, dof_count());
        return text;
    }
    std::snprintf(text, sizeof text, "branched grid%s, level %d, %zu elements, %zu degrees of freedom",
                  m_scene.solver.type == io::SolverType::shape_matching ? " moved by shape matching" : "", m_level, element_count(), dof_count());
    return text;
}

void DbgMethod::begin_tools(std::size_t tool_count)
{
    m_touch.resize(tool_count);
    m_touched.assign(tool_count, false);
    m_fresh.assign(tool_count, false);
    m_previous_section.resize(tool_count);
    m_marked_from.resize(tool_count);
    m_tool_reach.clear();
    m_region_reach.clear();
}

const contact::ContactResult& DbgMethod::touch(std::size_t tool, const io::ToolSpec& spec, const contact::PlacedShape& at,
                                               const contact::PlacedShape* from)
{
    const contact::ContactParameters parameters{spec.push_margin_mm, spec.contact_stiffness_n_per_mm};
    m_touch[tool] = cut::touch_surface(m_sim->surface(), m_sim->solver().positions(), at, parameters, from);
    m_tool_reach.push_back(at.world_bounds(k_sleep_tool_mm)); // wakes what sleeps near it
    if (m_scene.object.mixed_levels) m_region_reach.push_back(at.world_bounds(m_scene.object.mixed_levels->fine_radius_mm));
    m_touched[tool] = true;
    m_fresh[tool] = true;
    return m_touch[tool].contact;
}

CutFigures DbgMethod::follow(std::size_t tool, const io::ToolSpec& spec, const io::ToolPose& from, const contact::PlacedShape& at,
                             const CutOrder& order)
{
    // A separating tool's section, carried back to rest space (cut/voxel_cut.hpp): each frame
    // sweeps from the previous frame's section to this one.
    std::vector<Eigen::Vector3d> rest_section;
    if (spec.cut_mode == io::CutMode::separate) {
        rest_section = cut::section_polygon(*at.shape, 0.0, at);
        carry_to_rest(tool, spec, from, at, order, rest_section);
    }
    // Within a stroke that has cut, a frame that cuts nothing (its pressure fell under the
    // threshold as the object gave way) keeps the last cut's section, so the next cut goes on from
    // where that one ended: one continuous sheet (a curved stroke dragging a soft plate towards its
    // held rim paused for a few frames and opened its next cut 6 mm further on, a second sheet).
    std::vector<Eigen::Vector3d> previous = m_previous_section[tool];
    const bool paused = spec.cut_mode == io::CutMode::separate && !spec.two_phase && !order.cut && m_stroke[tool].has_cut;
    if (!paused) m_previous_section[tool] = rest_section;
    // Two-phase: the whole path marked since the first touch is cut at once.
    if (spec.two_phase) {
        if (!order.touching) {
            m_marked_from[tool].clear(); // let go: the next touch marks a new cut
        } else if (order.marking && !rest_section.empty()) {
            if (m_marked_from[tool].empty()) m_marked_from[tool] = rest_section;
            previous = m_marked_from[tool];
        }
    }
    if (!order.cut) return {};
    std::vector<grid::Coord> removed;
    std::vector<std::pair<grid::Coord, int>> faces;
    if (spec.cut_mode == io::CutMode::remove) {
        for (std::uint32_t v : cut::voxels_inside(m_sim->surface(), m_sim->solver().positions(), at, m_touch[tool].vertices))
            removed.push_back(m_grid->voxels().coord(v));
    } else {
        faces = cut::faces_crossed(m_grid->voxels(), cut::sweep_polygons(previous.empty() ? rest_section : previous, rest_section,
                                                                         at.orientation * Eigen::Vector3d::UnitY()));
        keep_one_sheet(m_stroke[tool], faces);
    }
    if (removed.empty() && faces.empty()) return {};
    if (spec.cut_mode == io::CutMode::separate) m_stroke[tool].has_cut = true;
    return apply(std::move(removed), std::move(faces));
}

void DbgMethod::keep_one_sheet(StrokeCarry& stroke, std::vector<std::pair<grid::Coord, int>>& faces)
{
    // Two frames of a stroke whose sections lie a fraction of a voxel apart can put one voxel on
    // either side of the sheet: the first opens the face before it, the next the face after it,
    // and the voxel between falls out as a sliver (a blade tilted 27 degrees drawn down through a
    // swinging rod). A stroke makes one sheet, in which no two faces are parallel a voxel apart, so
    // such a face is not opened: the material there is parted already.
    std::erase_if(faces, [&](const std::pair<grid::Coord, int>& f) {
        const auto& [c, axis] = f;
        std::array<int, 4> before{c.x(), c.y(), c.z(), axis}, after = before;
        --before[static_cast<std::size_t>(axis)];
        ++after[static_cast<std::size_t>(axis)];
        return stroke.opened.contains(before) || stroke.opened.contains(after);
    });
    for (const auto& [c, axis] : faces) stroke.opened.insert({c.x(), c.y(), c.z(), axis});
}

void DbgMethod::carry_to_rest(std::size_t tool, const io::ToolSpec& spec, const io::ToolPose& from, const contact::PlacedShape& at,
                              const CutOrder& order, std::vector<Eigen::Vector3d>& rest_section)
{
    Eigen::AlignedBox3d box;
    box.setEmpty();
    for (const Eigen::Vector3d& p : rest_section) box.extend(p);
    Eigen::Vector3d moved = cut::mean_displacement_mm(m_sim->surface(), m_sim->solver().positions(), box);
    // Across the blade's plane the carry stays where the stroke began: the mean displacement
    // around the blade jumps as the material bends under it or the sides part, and each jump
    // started a second sheet beside the first, with a slice between them (a drooping slab cut
    // by a tilted blade came apart in 29 pieces, 9 of them slivers). Along the plane it
    // follows the material, so the cut is as deep as the blade is in the material as it is.
    // A stroke ends when the tool leaves the scene, turns by more than 10 degrees in a frame or
    // has touched nothing for k_stroke_gap_s (it went to cut elsewhere).
    const Eigen::Vector3d normal = at.orientation * Eigen::Vector3d::UnitY();
    if (m_stroke.size() <= tool) m_stroke.resize(tool + 1);
    StrokeCarry& stroke = m_stroke[tool];
    stroke.untouched_s = order.touching ? 0.0 : stroke.untouched_s + m_scene.solver.dt_s;
    const bool goes_on = !m_previous_section[tool].empty() && stroke.going && normal.dot(stroke.normal) >= k_stroke_turn_cos &&
                         stroke.untouched_s < k_stroke_gap_s;
    if (!goes_on) stroke = {true, normal, normal.dot(moved), normal, 0.0, false, {}};
    stroke.normal = normal; // it may turn by up to 10 degrees a frame and go on
    moved += (stroke.across_mm - normal.dot(moved)) * normal;
    for (Eigen::Vector3d& p : rest_section) p -= moved;
    // The sheet is what the edge sweeps: a blade held at a slant to the way it moves (as a hand
    // holds it) would otherwise open each frame's section a little beside the last, a
    // staircase of sheets. The section is laid into the plane through the last one that
    // holds the edge and the way it moves (the blade's own plane when it moves along it).
    const bool edged = spec.shape == io::ToolShape::blade || spec.shape == io::ToolShape::scalpel;
    // A two-phase tool marks while the object is held still: nothing gives way under its edge.
    if (edged && order.cut && !order.marking) reach_past_edge(tool, at, spec.push_margin_mm, rest_section);
    const Eigen::Vector3d way = at.position - from.position_mm;
    if (goes_on && edged && way.allFinite() && way.norm() > 1e-9) {
        const Eigen::Vector3d swept = (at.orientation * Eigen::Vector3d::UnitX()).cross(way);
        if (swept.norm() > 0.2 * way.norm()) stroke.cut_normal = swept.normalized() * (swept.dot(normal) < 0.0 ? -1.0 : 1.0);
    }
    if (goes_on) { // through the last section's edge (its side lowest in the tool's frame), where it cuts
        const std::vector<Eigen::Vector3d>& last = m_previous_section[tool];
        const Eigen::Vector3d up = at.orientation * Eigen::Vector3d::UnitZ();
        double lowest = std::numeric_limits<double>::infinity();
        for (const Eigen::Vector3d& p : last) lowest = std::min(lowest, up.dot(p));
        Eigen::Vector3d through = Eigen::Vector3d::Zero();
        int on_edge = 0;
        for (const Eigen::Vector3d& p : last)
            if (up.dot(p) < lowest + 1e-6) {
                through += p;
                ++on_edge;
            }
        through /= on_edge;
        for (Eigen::Vector3d& p : rest_section) p -= stroke.cut_normal.dot(p - through) * stroke.cut_normal;
    }
}

void DbgMethod::reach_past_edge(std::size_t tool, const contact::PlacedShape& at, double margin_mm, std::vector<Eigen::Vector3d>& rest_section) const
{
    // The material an edge presses on is cut, not pushed ahead of it: carried by the material's
    // mean displacement, a section that pushes a compliant object along stays where it was in
    // rest space and cuts nothing more (a drooping slab was bent away under the blade, never cut
    // through). So the section reaches just past the rest position of every surface point in the
    // edge's contact zone (below the edge or less than the push margin above it, within the
    // blade's length): half a voxel and a little more, across the centres of the voxels under
    // that point. Pressed on, the cut goes a voxel deeper a frame; once the blade stops pressing,
    // the cut stops about one contact zone below its edge.
    if (!m_fresh[tool] || rest_section.empty()) return;
    const Eigen::Quaterniond to_tool = at.orientation.conjugate();
    double edge_z = std::numeric_limits<double>::infinity(); // the section's lowest side, tool frame
    double x_min = edge_z, x_max = -edge_z;                  // and its extent along the edge
    for (const Eigen::Vector3d& p : cut::section_polygon(*at.shape, 0.0, at)) {
        const Eigen::Vector3d local = to_tool * (p - at.position);
        edge_z = std::min(edge_z, local.z());
        x_min = std::min(x_min, local.x());
        x_max = std::max(x_max, local.x());
    }
    const Eigen::Vector3d h = 1e3 * m_grid->voxels().voxel_size_m();
    const Eigen::Vector3d up = at.orientation * Eigen::Vector3d::UnitZ();
    const double reach = 0.55 * h.dot(up.cwiseAbs()); // half a voxel's extent along `up`, and a little more
    double section_low = std::numeric_limits<double>::infinity();
    for (const Eigen::Vector3d& p : rest_section) section_low = std::min(section_low, up.dot(p));
    double deepest = section_low;
    const cut::SurfaceContact& touch = m_touch[tool];
    const std::vector<Eigen::Vector3d>& positions = m_sim->solver().positions();
    for (const contact::PointContact& c : touch.contact.points) {
        const std::uint32_t slot = touch.vertices[c.point];
        const Eigen::Vector3d local = to_tool * (m_sim->surface().vertex_mm(slot, positions) - at.position);
        if (local.z() > edge_z + margin_mm || local.x() < x_min || local.x() > x_max) continue;
        deepest = std::min(deepest, up.dot(m_sim->surface().vertex_rest_mm(slot)) - reach);
    }
    if (deepest < section_low)
        for (Eigen::Vector3d& p : rest_section) p -= (section_low - deepest) * up;
}

CutFigures DbgMethod::apply(std::vector<grid::Coord> removed, std::vector<std::pair<grid::Coord, int>> faces)
{
    CutFigures out;
    const CutTimings t = m_sim->apply_cut(*m_grid, removed, faces);
    out.grid_update_ms = t.grid_update_ms;
    out.remesh_ms = t.remesh_ms;
    out.fem_update_ms = t.fem_update_ms;
    out.removed_voxels = removed.size();
    out.separated_faces = faces.size();
    std::unordered_set<std::uint32_t> sides;
    for (const auto& [coord, axis] : faces)
        for (const grid::Coord& side : {coord, grid::Coord(coord + grid::Coord::Unit(axis))}) {
            const std::uint32_t v = m_grid->voxels().find(side);
            sides.insert(v);
            m_separated.insert(v);
        }
    out.separated_voxels = sides.size();
    out.cut_elements = removed.size() + faces.size();
    m_cuts.push_back({std::move(removed), std::move(faces)});
    std::fill(m_fresh.begin(), m_fresh.end(), false); // node numbers changed: contacts are carried over
    return out;
}

CutFigures DbgMethod::drill(std::size_t tool, const io::ToolSpec& spec, const contact::PlacedShape& at, double volume_mm3)
{
    if (m_drill_budget.size() <= tool) m_drill_budget.resize(tool + 1, 0.0);
    const std::vector<Eigen::Vector3d>& positions = m_sim->solver().positions();
    // The burr's teeth reach past its body through its contact zone (the push margin), and the
    // voxels it touches have their centres half a voxel deeper still.
    const Eigen::Vector3d h = 1e3 * m_grid->voxels().voxel_size_m();
    const double reach = spec.push_margin_mm + 0.5 * h.maxCoeff();
    const std::vector<std::uint32_t> within = cut::voxels_inside(m_sim->surface(), positions, at, m_touch[tool].vertices, reach);
    if (within.empty()) {
        m_drill_budget[tool] = 0.0; // no banking of removal while the burr touches nothing
        return {};
    }
    const double voxel_mm3 = h.prod();
    m_drill_budget[tool] += volume_mm3;
    const auto wanted = static_cast<std::size_t>(std::floor(m_drill_budget[tool] / voxel_mm3));
    if (wanted == 0) return {};
    // The voxels nearest the burr's body go first (slot order breaks ties, so runs repeat).
    std::vector<std::pair<double, std::uint32_t>> nearest;
    nearest.reserve(within.size());
    for (std::uint32_t v : within) nearest.emplace_back(at.signed_distance(m_sim->surface().voxel_centre_mm(v, positions)), v);
    const std::size_t taken = std::min(wanted, nearest.size());
    std::partial_sort(nearest.begin(), nearest.begin() + static_cast<std::ptrdiff_t>(taken), nearest.end());
    m_drill_budget[tool] = taken < wanted ? 0.0 : m_drill_budget[tool] - static_cast<double>(taken) * voxel_mm3;
    std::vector<grid::Coord> removed;
    for (std::size_t k = 0; k < taken; ++k) removed.push_back(m_grid->voxels().coord(nearest[k].second));
    return apply(std::move(removed), {});
}

void DbgMethod::wet(std::size_t tool, double water)
{
    fem::ImplicitSolver& solver = m_sim->solver();
    for (std::uint32_t e : m_touch[tool].elements) solver.set_water(e, solver.water(e) + water);
}

void DbgMethod::end_tools()
{
    // Two levels: the fine region follows the tools before the forces go onto the model's nodes.
    Stopwatch region_clock;
    m_region_move_ms = 0.0;
    if (m_sim->follow_tools(m_region_reach)) {
        std::fill(m_fresh.begin(), m_fresh.end(), false);
        m_region_move_ms = region_clock.lap();
        ++m_region_moves;
    }
    m_region_reach.clear();
    // The forces for the next step, on the model as it now is.
    std::vector<fem::NodeContact> nodes;
    for (std::size_t k = 0; k < m_touch.size(); ++k) {
        if (!m_touched[k]) continue;
        if (!m_fresh[k]) m_touch[k].nodes = cut::node_contacts(m_sim->surface(), m_touch[k]); // onto the rebuilt model's nodes
        cut::merge_node_contacts(nodes, m_touch[k].nodes);
    }
    // Obstacles and pieces push along their normals as pair contacts, the obstacles' first.
    const double voxel_mm = 1e3 * m_grid->voxels().voxel_size_m().maxCoeff();
    std::vector<fem::PairContact> pairs;
    m_obstacle_force.setZero();
    const fem::ImplicitSolver& solver = m_sim->solver();
    std::vector<Eigen::Vector3d> ends;
    if (!m_obstacles.empty() || m_scene.piece_contact.enabled) ends = solver.free_step_positions(m_scene.solver.dt_s);
    for (std::size_t k = 0; k < m_obstacles.size(); ++k) {
        cut::SurfaceContact c = cut::touch_obstacle(m_sim->surface(), solver.positions(), ends, solver.velocities(), m_scene.solver.dt_s,
                                                    m_obstacles[k], m_anchors[k], obstacle_skin_mm(voxel_mm));
        m_obstacle_force += friction_force_n(c.contact); // the push: after the step
        cut::merge_node_contacts(nodes, c.nodes);
        std::move(c.pairs.begin(), c.pairs.end(), std::back_inserter(pairs));
    }
    m_obstacle_pairs = pairs.size();
    m_sim->solver().set_contact(std::move(nodes));
    m_piece_contact = {};
    if (m_scene.piece_contact.enabled) {
        Stopwatch clock;
        cut::PieceContact c = cut::touch_pieces(m_sim->surface(), solver.positions(), ends, piece_contact_parameters(m_scene, voxel_mm));
        m_piece_contact = {true, c.faces.size() + c.edges.size(), c.edges.size(), c.patch.start_mm.size(), 0.0, 0.0, deepest_mm(c.faces, c.edges)}; // force_n: after the step
        // A piece pressed by one that moves wakes as a tool's reach would wake it.
        auto wake = [&](std::uint32_t v) {
            m_tool_reach.emplace_back(c.patch.start_mm[v] - Eigen::Vector3d::Constant(voxel_mm), c.patch.start_mm[v] + Eigen::Vector3d::Constant(voxel_mm));
        };
        for (const contact::FaceContact& f : c.faces) wake(f.vertex);
        for (const contact::EdgeContact& e : c.edges) wake(e.edge[0]);
        std::move(c.pairs.begin(), c.pairs.end(), std::back_inserter(pairs));
        m_piece_contact.ms = clock.lap();
    }
    m_sim->solver().set_pair_contact(std::move(pairs));
    m_sim->set_tool_reach(std::move(m_tool_reach));
    m_tool_reach.clear();
}

StepFigures DbgMethod::step()
{
    const fem::StepStats s = m_sim->step();
    m_obstacle_force += m_sim->solver().pair_contact_force(0, m_obstacle_pairs).vector_n;
    if (m_piece_contact.enabled) m_piece_contact.force_n = m_sim->solver().pair_contact_force(m_obstacle_pairs, SIZE_MAX).magnitude_n;
    StepFigures out;
    out.step_ms = s.step_ms;
    out.assembly_ms = s.assembly_ms;
    out.solve_ms = s.solve_ms;
    out.cg_iterations = s.cg_iterations;
    out.newton_iterations = s.newton_iterations;
    out.residual = s.residual;
    out.converged = s.converged;
    out.substeps = s.substeps;
    out.kinetic_energy_j = s.kinetic_energy_j;
    out.elastic_energy_j = s.elastic_energy_j;
    const fem::ElementShapes shapes = fem::element_shapes(m_sim->model(), m_sim->solver().positions());
    out.inverted_elements = shapes.inverted;
    out.max_stretch = shapes.max_stretch;
    out.most_stretched_mm = {1e3 * shapes.most_stretched_m.x(), 1e3 * shapes.most_stretched_m.y(), 1e3 * shapes.most_stretched_m.z()};
    out.energy_projected = s.energy_projected;
    out.recovered = s.converged && (s.newton_iterations > 0 || s.substeps > 0);
    out.preconditioner_fallback = newly_failed(m_sim->solver().fallback_note(), m_fallback_reported);
    out.asleep_pieces = m_sim->asleep_piece_count();
    return out;
}

surface::SurfaceMesh DbgMethod::surface_mesh() const { return m_sim->surface().mesh(m_sim->solver().positions()); }

std::optional<io::VtuMesh> DbgMethod::fem_mesh() const { return dbg_fem_mesh(*m_sim); }

grid::LabelGrid DbgMethod::rest_voxels() const
{
    const grid::FineVoxels& voxels = grid().voxels(); // coordinates in the source's index space
    grid::LabelGrid out(voxels.index_to_world());
    out.copy_metadata(*m_labels);
    for (std::uint32_t v = 0; v < voxels.slots(); ++v)
        if (voxels.alive(v)) out.set(voxels.coord(v), voxels.label(v));
    return out;
}

std::vector<SurfaceMark> DbgMethod::surface_marks() const
{
    std::vector<SurfaceMark> out;
    for (const surface::SurfaceVertex& v : m_sim->surface().embedded().vertices()) // the mesh lists the slots in use, in order
        if (v.users) out.push_back(m_uncut.contains(v.key) ? SurfaceMark::surface : SurfaceMark::cut);
    return out;
}

std::vector<float> DbgMethod::surface_wetness() const
{
    const cut::ModelSurface& surface = m_sim->surface();
    const auto& slots = surface.embedded().vertices();
    std::vector<float> out;
    for (std::uint32_t slot = 0; slot < slots.size(); ++slot) {
        if (!slots[slot].users) continue;
        const std::uint32_t e = surface.vertex_element(slot);
        out.push_back(e < m_sim->model().elements().size() ? static_cast<float>(m_sim->solver().water(e)) : 0.0f);
    }
    return out;
}

std::vector<Eigen::Vector3d> DbgMethod::surface_displacements_mm() const
{
    const std::vector<Eigen::Vector3d> u = m_sim->surface().displacements(m_sim->solver().positions());
    const auto& slots = m_sim->surface().embedded().vertices();
    std::vector<Eigen::Vector3d> out;
    for (std::size_t i = 0; i < slots.size(); ++i)
        if (slots[i].users) out.push_back(1e3 * u[i]);
    return out;
}

std::vector<std::uint64_t> DbgMethod::surface_keys() const
{
    std::vector<std::uint64_t> out;
    for (const surface::SurfaceVertex& v : m_sim->surface().embedded().vertices())
        if (v.users) out.push_back(v.key);
    return out;
}

void DbgMethod::sample_surface(const Eigen::AlignedBox3d& box, const io::ToolSpec&, contact::SurfacePoints& out) const
{
    const fem::ImplicitSolver& solver = m_sim->solver();
    const auto* shape_matching = dynamic_cast<const shape::ShapeMatching*>(solver.integrator());
    if (!shape_matching) {
        cut::sample_surface(m_sim->surface(), solver.positions(), box, out);
        return;
    }
    // Stable constraint particle coupling (docs/shape-matching.md): the haptic thread touches the
    // surface where the clusters put it (their goals), each point held there as stiffly as its
    // clusters hold their particles: a particle's weights s (N/m) over the area it stands for, h^2
    // (a face particle of a full block lies in four clusters of kappa = mu h: s = 4 mu h, so a patch
    // of area a pressed in with the goals held costs 4 mu a / h N/mm, the paper's kappa (g - x)).
    const fem::HexModel& model = m_sim->model();
    std::vector<double> scale(model.elements().size());
    for (std::uint32_t e = 0; e < scale.size(); ++e) scale[e] = solver.stiffness_scale(e, model.elements()[e].material);
    std::vector<Eigen::Vector3d> goal;
    std::vector<double> stiffness;
    shape_matching->particle_goals(solver.positions(), scale, goal, stiffness);
    const Eigen::Vector3d voxel = m_grid->voxels().voxel_size_m();
    const double h = std::ldexp(std::cbrt(voxel.prod()), m_level); // the element's edge, m
    for (double& s : stiffness) s *= 1e-7 / (h * h); // N/m per m^2 -> N/mm per cm^2
    cut::sample_surface(m_sim->surface(), goal, box, out, &stiffness);
}

void DbgMethod::sample_pressed_surface(const Eigen::AlignedBox3d& box, const io::ToolSpec&, contact::SurfacePoints& out) const
{
    cut::sample_surface(m_sim->surface(), m_sim->solver().positions(), box, out);
}

std::optional<double> DbgMethod::contact_compliance_mm_per_n(std::size_t tool)
{
    constexpr int k_compliance_frames = 10;
    if (tool >= m_touched.size() || !m_touched[tool] || m_touch[tool].nodes.empty()) {
        if (tool < m_compliance.size()) m_compliance[tool] = {};
        return std::nullopt;
    }
    if (m_compliance.size() <= tool) m_compliance.resize(tool + 1);
    Compliance& c = m_compliance[tool];
    if (c.mm_per_n && ++c.age < k_compliance_frames) return c.mm_per_n;
    c.age = 0;
    // The contact's load, one newton in all, spread over the nodes as it is.
    const std::vector<fem::NodeContact>& nodes = m_touch[tool].nodes;
    fem::ImplicitSolver& solver = m_sim->solver();
    Eigen::Vector3d total = Eigen::Vector3d::Zero();
    for (const fem::NodeContact& n : nodes) total += n.force_n;
    if (!(total.norm() > 1e-9)) return c.mm_per_n = std::nullopt;
    std::vector<Eigen::Vector3d> load(solver.positions().size(), Eigen::Vector3d::Zero());
    for (const fem::NodeContact& n : nodes) load[n.node] += n.force_n / total.norm();
    const std::vector<Eigen::Vector3d> u = solver.response(load);
    if (u.empty()) return c.mm_per_n = std::nullopt;
    double compliance = 0.0; // m/N
    for (std::size_t i = 0; i < u.size(); ++i) compliance += load[i].dot(u[i]);
    if (!(compliance > 0.0)) return c.mm_per_n = std::nullopt;
    return c.mm_per_n = 1e3 * compliance;
}

std::size_t DbgMethod::piece_count() const { return cut::piece_count(m_sim->model()); }

void DbgMethod::add_frame_figures(nlohmann::json& frame) const
{
    if (m_scene.object.mixed_levels) frame["fine_region"] = {{"cells", m_sim->region().size()}, {"move_ms", m_region_move_ms}};
}

void DbgMethod::add_summary_figures(nlohmann::json& summary) const
{
    if (m_scene.object.mixed_levels) summary["fine_region_moves"] = m_region_moves;
    std::size_t wet = 0;
    for (std::uint32_t e = 0; e < m_sim->model().elements().size(); ++e) wet += m_sim->solver().water(e) > 0.0;
    summary.update({{"voxels", m_grid->voxels().alive_count()},
                    {"wet_elements", wet},
                    {"mass_kg", m_grid->total_mass_kg()},
                    {"separated_voxels", m_separated.size()}, // each voxel once, however many of its faces opened
                    {"held_pieces", m_sim->held_piece_count()},
                    {"rigid_elements", m_sim->rigid_element_count()},
                    {"rigid_bodies", m_sim->rigid_body_count()}});
}

std::unique_ptr<Method> DbgMethod::at_level(int level) const
{
    auto out = std::make_unique<DbgMethod>(m_scene, m_labels, level, m_grid_levels);
    for (const CutRecord& r : m_cuts) out->apply(r.removed, r.faces);
    out->m_separated = m_separated;
    return out;
}

bool DbgMethod::move_to_level(int level, io::PreconditionerChoice preconditioner)
{
    if (level == m_level && preconditioner == m_scene.solver.preconditioner) return true;
    if (level < 1 || m_level < 1 || level > m_grid->max_level() || m_scene.object.mixed_levels) return false; // two levels: not yet
    auto moved = std::make_unique<DbgSimulation>(*m_sim, level, preconditioner); // throws with m_sim untouched
    m_sim = std::move(moved);
    m_level = level;
    m_scene.solver.preconditioner = preconditioner;
    std::fill(m_fresh.begin(), m_fresh.end(), false); // contacts go onto the new level's nodes
    return true;
}

std::size_t DbgMethod::cut_count() const { return m_cuts.size(); }

nlohmann::json DbgMethod::cuts_since(std::size_t from) const
{
    nlohmann::json out = nlohmann::json::array();
    for (std::size_t c = from; c < m_cuts.size(); ++c) {
        nlohmann::json removed = nlohmann::json::array(), faces = nlohmann::json::array();
        for (const grid::Coord& v : m_cuts[c].removed) removed.push_back({v.x(), v.y(), v.z()});
        for (const auto& [v, axis] : m_cuts[c].faces) faces.push_back({v.x(), v.y(), v.z(), axis});
        out.push_back({{"removed", std::move(removed)}, {"faces", std::move(faces)}});
    }
    return out;
}

namespace {
std::string coord_text(const grid::Coord& v)
{
    return "(" + std::to_string(v.x()) + ", " + std::to_string(v.y()) + ", " + std::to_string(v.z()) + ")";
}
} // namespace

void DbgMethod::replay_cuts(const nlohmann::json& cuts)
{
    // A journal may be damaged: every voxel is checked against the grid before the cut is made.
    const auto coord = [](const nlohmann::json& a, std::size_t n) {
        if (!a.is_array() || a.size() != n) throw InputError("expected an array of " + std::to_string(n) + " integers");
        for (const auto& x : a)
            if (!x.is_number_integer()) throw InputError("expected an array of " + std::to_string(n) + " integers");
        return grid::Coord(a[0].get<int>(), a[1].get<int>(), a[2].get<int>());
    };
    if (!cuts.is_array()) throw InputError("the cuts are not an array");
    for (std::size_t c = 0; c < cuts.size(); ++c) {
        const nlohmann::json& cut = cuts[c];
        const std::string where = "cut " + std::to_string(c) + ": ";
        try {
            if (!cut.is_object() || !cut.contains("removed") || !cut.contains("faces") || !cut["removed"].is_array() ||
                !cut["faces"].is_array())
                throw InputError("expected {\"removed\": [...], \"faces\": [...]}");
            std::vector<grid::Coord> removed;
            for (const auto& v : cut["removed"]) {
                removed.push_back(coord(v, 3));
                if (m_grid->voxels().find(removed.back()) == grid::FineVoxels::missing)
                    throw InputError("removes voxel " + coord_text(removed.back()) + ", which the object does not have");
            }
            std::vector<std::pair<grid::Coord, int>> faces;
            for (const auto& f : cut["faces"]) {
                if (!f.is_array() || f.size() != 4 || !f[3].is_number_integer() || f[3].get<int>() < 0 || f[3].get<int>() > 2)
                    throw InputError("a face is [i, j, k, axis] with axis 0, 1 or 2");
                const grid::Coord v = coord(nlohmann::json{f[0], f[1], f[2]}, 3);
                const int axis = f[3].get<int>();
                if (m_grid->voxels().find(v) == grid::FineVoxels::missing ||
                    m_grid->voxels().find(grid::Coord(v + grid::Coord::Unit(axis))) == grid::FineVoxels::missing)
                    throw InputError("opens a face of voxel " + coord_text(v) + " that the object does not have");
                faces.emplace_back(v, axis);
            }
            (void)apply(std::move(removed), std::move(faces));
        } catch (const InputError& e) {
            throw InputError(where + e.what());
        }
    }
}

std::vector<double> DbgMethod::motion() const
{
    const fem::ImplicitSolver& s = m_sim->solver();
    std::vector<double> out;
    for (const auto* field : {&s.positions(), &s.velocities()})
        for (const Eigen::Vector3d& p : *field) out.insert(out.end(), p.data(), p.data() + 3);
    const auto elements = static_cast<std::uint32_t>(m_sim->model().elements().size());
    for (std::uint32_t e = 0; e < elements; ++e) out.push_back(s.water(e));
    for (std::uint32_t e = 0; e < elements; ++e) {
        const Eigen::Matrix3d p = s.plastic_strain(e);
        out.insert(out.end(), p.data(), p.data() + 9);
    }
    // Two levels: the fine region the state is on, its cells then their count, last.
    if (m_scene.object.mixed_levels) {
        for (const grid::Coord& c : m_sim->region()) out.insert(out.end(), {double(c.x()), double(c.y()), double(c.z())});
        out.push_back(static_cast<double>(m_sim->region().size()));
    }
    return out;
}

void DbgMethod::set_motion(const std::vector<double>& numbers)
{
    std::size_t region_numbers = 0;
    if (m_scene.object.mixed_levels) {
        const double count = numbers.empty() ? -1.0 : numbers.back();
        if (!(count >= 0.0 && count == std::floor(count) && 3.0 * count + 1.0 <= static_cast<double>(numbers.size())))
            throw InputError("the state does not end with the fine region of a run on two levels");
        const auto cells = static_cast<std::size_t>(count);
        region_numbers = 3 * cells + 1;
        const double* at = numbers.data() + numbers.size() - region_numbers;
        RegionCells region;
        for (std::size_t c = 0; c < cells; ++c, at += 3) region.emplace_back(static_cast<int>(at[0]), static_cast<int>(at[1]), static_cast<int>(at[2]));
        m_sim->set_region(std::move(region));
    }
    fem::ImplicitSolver& s = m_sim->solver();
    const std::size_t nodes = s.positions().size();
    const auto elements = static_cast<std::uint32_t>(m_sim->model().elements().size());
    check_motion(numbers, 6 * nodes + 10 * std::size_t{elements} + region_numbers);
    const double* at = numbers.data();
    for (auto* field : {&s.positions(), &s.velocities()})
        for (Eigen::Vector3d& p : *field) {
            p = Eigen::Vector3d(at[0], at[1], at[2]);
            at += 3;
        }
    for (std::uint32_t e = 0; e < elements; ++e) s.set_water(e, *at++);
    for (std::uint32_t e = 0; e < elements; ++e) {
        s.set_plastic_strain(e, Eigen::Map<const Eigen::Matrix3d>(at));
        at += 9;
    }
}

std::unique_ptr<Checkpoint> DbgMethod::checkpoint() const
{
    auto c = std::make_unique<DbgCheckpoint>();
    const fem::ImplicitSolver& s = m_sim->solver();
    c->cuts = m_cuts.size();
    c->level = m_level;
    c->preconditioner = m_scene.solver.preconditioner;
    c->positions = s.positions();
    c->velocities = s.velocities();
    for (std::uint32_t e = 0; e < m_sim->model().elements().size(); ++e) {
        c->water.push_back(s.water(e));
        c->plastic.push_back(s.plastic_strain(e));
    }
    c->separated = m_separated;
    c->region = m_sim->region();
    return c;
}

void DbgMethod::restore(const Checkpoint& checkpoint)
{
    const auto& c = dynamic_cast<const DbgCheckpoint&>(checkpoint);
    // The grid as it was after the first c.cuts cuts: rebuilt from the voxels and the cuts
    // replayed, the same model node for node.
    m_sim.reset();
    m_level = c.level;
    m_scene.solver.preconditioner = c.preconditioner;
    m_grid = std::make_unique<grid::BranchedGrid>(build_scene_grid(m_scene, *m_labels, m_grid_levels));
    m_sim = std::make_unique<DbgSimulation>(m_scene, *m_grid, m_level);
    m_cuts.resize(std::min(m_cuts.size(), c.cuts));
    for (const CutRecord& r : m_cuts) m_sim->apply_cut(*m_grid, r.removed, r.faces);
    m_sim->set_region(c.region);
    fem::ImplicitSolver& s = m_sim->solver();
    if (s.positions().size() == c.positions.size()) {
        s.positions() = c.positions;
        s.velocities() = c.velocities;
        for (std::uint32_t e = 0; e < c.water.size() && e < m_sim->model().elements().size(); ++e) {
            s.set_water(e, c.water[e]);
            s.set_plastic_strain(e, c.plastic[e]);
        }
    }
    m_separated = c.separated;
    for (auto& section : m_previous_section) section.clear();
    for (auto& section : m_marked_from) section.clear();
    m_stroke.clear();
}

} // namespace vox::sim
