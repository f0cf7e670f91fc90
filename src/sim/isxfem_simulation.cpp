#include "sim/isxfem_simulation.hpp"

#include "sim/dbg_simulation.hpp"
#include "core/error.hpp"
#include "core/union_find.hpp"
#include "cut/model_surface.hpp"
#include "contact/box_grid.hpp"
#include "cut/piece_contact.hpp"
#include "cut/pieces.hpp"
#include "sim/rigid_parts.hpp"
#include "sim/supports.hpp"
#include "fem/hex_model.hpp"
#include "fem/rest_cholesky.hpp"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <limits>

namespace vox::sim {

IsxfemSimulation::IsxfemSimulation(const io::Scene& scene, const grid::BranchedGrid& grid, int level) : m_grid(grid)
{
    if (scene.solver.mode != io::SolverMode::dynamic)
        throw scene.error("solver.mode", "\"isxfem\" simulates dynamically only so far; use \"dynamic\" or \"type\": \"dbg\"");
    if (!scene.loads.empty()) throw scene.error("loads", "\"isxfem\" does not apply loads yet; use \"type\": \"dbg\"");
    if (!scene.wet_regions.empty()) throw scene.error("wet_regions", "\"isxfem\" does not wet yet; use \"type\": \"dbg\"");
    const io::MaterialTable table = io::material_table(scene);
    for (std::size_t m = 0; m < table.scene_materials.size(); ++m)
        if (table.scene_materials[m].plasticity)
            throw scene.error("materials", "\"isxfem\" has no plasticity yet; use \"type\": \"dbg\"");

    const fem::HexModel hex(grid, level);
    isxfem::GridTets tets = isxfem::tets_from_model(grid, hex);
    m_model = std::make_unique<isxfem::XfemModel>(tets.mesh, std::move(tets.materials), std::move(tets.material), scene.solver.isxfem_k);
    isxfem::XfemOptions& o = m_options;
    o.dt_s = scene.solver.dt_s;
    o.cg_tolerance = scene.solver.cg_tolerance;
    o.cg_max_iterations = scene.solver.cg_max_iterations;
    o.rayleigh_mass_per_s = scene.solver.rayleigh_mass_per_s;
    o.rayleigh_stiffness_s = scene.solver.rayleigh_stiffness_s;
    o.regularisation_lambda = scene.solver.isxfem_regularisation_lambda;
    o.regularisation_threshold = scene.solver.isxfem_regularisation_threshold;
    m_closure = std::make_unique<isxfem::CutClosure>(*m_model);
    if (scene.solver.preconditioner == io::PreconditionerChoice::multigrid)
        throw scene.error("solver.preconditioner", "\"isxfem\" has no multigrid; use \"auto\", \"cholesky\" or \"jacobi\"");
    // The warped factor (patched across cuts and taken again when that or the turning costs more)
    // unless the scene asks for Jacobi.
    m_factor = scene.solver.preconditioner != io::PreconditionerChoice::jacobi;
    m_gravity = scene.gravity_m_s2;
    for (std::size_t k = 0; k < scene.constraints.size(); ++k) {
        const io::Constraint& c = scene.constraints[k];
        const unsigned axes = (c.held_axes[0] ? 1u : 0u) | (c.held_axes[1] ? 2u : 0u) | (c.held_axes[2] ? 4u : 0u);
        BoxMaterial box(c.box_min_mm, c.box_max_mm);
        box.update(grid, level, nullptr);
        const std::vector<std::uint32_t> nodes = box.supported_nodes(hex);
        if (nodes.empty()) throw scene.error("constraints[" + std::to_string(k) + "].box_mm", "holds no voxel centre of the object");
        for (std::uint32_t n : nodes) m_fixed.emplace_back(n, axes);
    }
    // Rigid material holds the soft material of its piece, so "hold" leaves such pieces to it.
    const std::vector<std::uint32_t> piece = cut::element_pieces(hex);
    const std::vector<RigidContent> rigid_element = rigid_content(grid, hex, rigid_materials(scene));
    if (scene.object.unheld == io::UnheldPieces::hold) {
        // Pieces no constraint reaches stay where they are: every node of theirs fixed.
        std::vector<unsigned char> constrained(hex.node_count(), 0);
        for (const auto& [n, axes] : m_fixed) constrained[n] = 1;
        const std::vector<unsigned char> unheld = cut::unheld_elements(hex, anchoring_nodes(hex, piece, rigid_element, constrained), m_held_pieces);
        std::vector<unsigned char> held(hex.node_count(), 0);
        for (std::uint32_t e = 0; e < hex.elements().size(); ++e)
            if (unheld[e])
                for (std::uint32_t n : hex.elements()[e].dof_node) held[n] = 1;
        for (std::uint32_t n = 0; n < hex.node_count(); ++n)
            if (held[n]) m_fixed.emplace_back(n, 7u);
    }
    // Rigid material is held in place, with the soft material attached to it.
    std::vector<unsigned char> held(hex.node_count(), 0);
    for (const auto& [n, axes] : m_fixed) held[n] = 1;
    const RigidParts rigid = rigid_parts(hex, piece, rigid_element, held, false);
    m_rigid_elements = rigid.rigid_elements;
    if (!rigid.bodies.empty())
        throw scene.error("materials", "a piece of rigid material that nothing holds would move as a rigid body, which \"isxfem\" "
                                       "cannot do yet; hold it (a constraint, or \"unheld_pieces\": \"hold\") or use \"type\": \"dbg\"");
    for (std::uint32_t n = 0; n < hex.node_count(); ++n)
        if (rigid.anchored[n]) m_fixed.emplace_back(n, 7u);
    make_solver();

    // The surface, each used vertex located in a tetrahedron of its element.
    m_surface = std::make_unique<surface::EmbeddedSurface>(grid, std::max(level, 1));
    smooth_scene_surface(scene, grid, *m_surface);
    const cut::ModelSurface embedding(grid, hex, *m_surface);
    for (std::uint32_t v = 0; v < m_surface->vertices().size(); ++v) {
        if (m_surface->vertices()[v].users == 0) continue;
        Embedded e;
        e.rest_m = embedding.vertex_rest_mm(v) * 1e-3;
        e.key = m_surface->vertices()[v].key;
        std::tie(e.tet, e.bary) = isxfem::locate(m_model->mesh(), embedding.vertex_element(v), e.rest_m);
        m_vertices.push_back(e);
    }
    m_rest = m_surface->mesh(grid); // the used vertices in slot order, as m_vertices
}

isxfem::CutReport IsxfemSimulation::cut(const isxfem::CutSurface& surface, std::size_t new_from, int extend)
{
    CutCall call{extend, new_from, {}};
    const std::size_t known = extend >= 0 && extend < m_model->cut_count() ? m_model->cut_surface(extend).patches().size() : 0;
    const auto& patches = surface.patches();
    call.patches.assign(patches.begin() + static_cast<std::ptrdiff_t>(std::min(known, patches.size())), patches.end());
    const isxfem::CutReport r = m_model->cut(surface, new_from, extend);
    if (r.cut_tets > 0) m_solver->model_changed();
    m_cut_log.push_back(std::move(call));
    return r;
}

isxfem::CutReport IsxfemSimulation::replay(const CutCall& call)
{
    if (call.extend < -1 || call.extend >= m_model->cut_count())
        throw InputError("extends cut " + std::to_string(call.extend) + ", but the object has " +
                         std::to_string(m_model->cut_count()) + " cut(s)");
    isxfem::CutSurface surface = call.extend >= 0 ? m_model->cut_surface(call.extend) : isxfem::CutSurface();
    for (const isxfem::CutPatch& p : call.patches) {
        bool finite = p.normal.allFinite() && std::abs(p.normal.norm() - 1.0) < 1e-6;
        for (const Eigen::Vector3d& c : p.corners) finite = finite && c.allFinite();
        if (!finite) throw InputError("a patch with a non-finite corner or a normal that is not a unit vector");
        surface.add(p);
    }
    if (call.new_from > surface.patches().size())
        throw InputError("its new patches begin at " + std::to_string(call.new_from) + ", past its " +
                         std::to_string(surface.patches().size()) + " patches");
    return cut(surface, call.new_from, call.extend);
}

std::vector<Eigen::Vector3d> IsxfemSimulation::surface_displacements() const
{
    std::vector<Eigen::Vector3d> u;
    u.reserve(m_vertices.size());
    for (const Embedded& v : m_vertices) {
        u.push_back(m_solver->position(v.tet, v.bary, side_of(v.tet, v.bary)) - v.rest_m);
    }
    return u;
}

int IsxfemSimulation::side_of(std::size_t tet, const std::array<double, 4>& bary) const
{
    return static_cast<int>(m_model->elements()[tet].region_at(bary));
}

Eigen::Vector3d IsxfemSimulation::mean_displacement_mm(const Eigen::AlignedBox3d& box) const
{
    const auto& rest = m_model->mesh().nodes;
    const auto& x = m_solver->state();
    Eigen::Vector3d sum = Eigen::Vector3d::Zero();
    std::size_t count = 0;
    for (const isxfem::XfemElement& el : m_model->elements()) {
        Eigen::AlignedBox3d deformed;
        deformed.setEmpty();
        for (std::uint32_t n : el.node) deformed.extend(1e3 * x[n]);
        if (!deformed.intersects(box)) continue;
        for (std::uint32_t n : el.node) sum += 1e3 * (x[n] - rest[n]);
        count += 4;
    }
    return count ? Eigen::Vector3d(sum / static_cast<double>(count)) : Eigen::Vector3d::Zero();
}

std::vector<std::uint64_t> IsxfemSimulation::surface_keys() const
{
    std::vector<std::uint64_t> keys;
    keys.reserve(m_vertices.size());
    for (const Embedded& v : m_vertices) keys.push_back(v.key);
    return keys;
}


IsxfemSimulation::~IsxfemSimulation() = default;

void IsxfemSimulation::make_solver()
{
    m_solver = std::make_unique<isxfem::XfemSolver>(*m_model, m_options);
    if (m_factor) {
        auto factor = std::make_unique<fem::RestCholesky>(Eigen::Matrix3d::Identity(), 25, fem::RestCholesky::background_flops_here());
        factor->set_exact_cuts(false); // a cut changes rows beyond the blocks it names (fem/rest_cholesky.hpp)
        m_solver->set_preconditioner(std::move(factor));
    }
    m_solver->set_gravity(m_gravity);
    for (const auto& [node, axes] : m_fixed) m_solver->fix(node, axes);
}

IsxfemSimulation::State IsxfemSimulation::state() const
{
    return {*m_model, m_solver->state(), m_solver->velocities(), m_cut_log};
}

void IsxfemSimulation::restore(const State& s)
{
    // The model as it was (its cuts), a solver built anew on it (its matrix pattern, enriched
    // blocks and factor follow the model), and the state; the closed surface is made again.
    m_solver.reset();
    *m_model = s.model; // in place: the closure keeps its reference
    m_closure = std::make_unique<isxfem::CutClosure>(*m_model);
    make_solver();
    m_solver->set_state(s.x, s.v);
    m_cut_log = s.cut_log;
    m_closed_vertices.clear();
}

void IsxfemSimulation::refresh_closed_surface() const
{
    // It depends on the cuts only (material points and rest triangles): rebuilt when they change.
    if (m_closed_revision == m_model->revision() && !m_closed_vertices.empty()) return;
    m_closed_vertices.clear();
    m_closed_vertices.reserve(m_vertices.size());
    for (std::size_t k = 0; k < m_vertices.size(); ++k) {
        const Embedded& e = m_vertices[k];
        m_closed_vertices.push_back({e.tet, e.bary, side_of(e.tet, e.bary), e.rest_m, m_rest.labels[k]});
    }
    m_closed_triangles = m_rest.triangles;
    m_closed_crack.assign(m_closed_triangles.size(), -1);
    m_closure_counts = {};
    for (int cut = 0; cut < m_model->cut_count(); ++cut)
        m_closure_counts += m_closure->close(cut, m_closed_vertices, m_closed_triangles, &m_closed_crack);
    m_closed_revision = m_model->revision();
}

std::size_t IsxfemSimulation::surface_vertex_count() const
{
    refresh_closed_surface();
    return m_closed_vertices.size();
}

isxfem::ClosureCounts IsxfemSimulation::closure_counts() const
{
    refresh_closed_surface();
    return m_closure_counts;
}

surface::SurfaceMesh IsxfemSimulation::surface_mesh() const
{
    refresh_closed_surface();
    surface::SurfaceMesh out;
    out.triangles = m_closed_triangles;
    for (const isxfem::SurfacePoint& v : m_closed_vertices) {
        out.positions.push_back(1e3 * m_solver->position(v.tet, v.bary, v.side));
        out.labels.push_back(v.label);
    }
    return out;
}

std::vector<IsxfemSimulation::Mark> IsxfemSimulation::surface_marks() const
{
    refresh_closed_surface();
    // Around such a tetrahedron (its nodes' tetrahedra): one alone is a speck in a picture.
    std::vector<unsigned char> coupled_node(m_model->node_count(), 0);
    for (const isxfem::XfemElement& el : m_model->elements())
        if (el.crossed || el.cut_left_out)
            for (std::uint32_t n : el.node) coupled_node[n] = 1;
    std::vector<Mark> out;
    out.reserve(m_closed_vertices.size());
    for (std::size_t v = 0; v < m_closed_vertices.size(); ++v) { // the closure appends what it makes after the object's own
        const isxfem::XfemElement& el = m_model->elements()[m_closed_vertices[v].tet];
        const bool coupled = std::any_of(el.node.begin(), el.node.end(), [&](std::uint32_t n) { return coupled_node[n] != 0; });
        out.push_back(coupled ? Mark::coupled : v >= m_vertices.size() ? Mark::cut : Mark::surface);
    }
    return out;
}

/// The closed surface's vertices within a box: their material points, deformed positions (mm),
/// areas and normals, and the triangles with all three corners among them.
struct IsxfemSimulation::NearSurface {
    const std::vector<isxfem::SurfacePoint>* vertices = nullptr; ///< all of the closed surface's
    std::vector<std::uint32_t> near;              ///< the ones in the box
    std::vector<Eigen::Vector3d> positions, normals;
    std::vector<double> areas;
    std::vector<Eigen::Vector3i> triangles;       ///< among `near` (indices into it)
};

IsxfemSimulation::NearSurface IsxfemSimulation::near_surface(const Eigen::AlignedBox3d& reach, double closed_walls_mm) const
{
    NearSurface out;
    refresh_closed_surface();
    out.vertices = &m_closed_vertices;
    const std::vector<isxfem::SurfacePoint>& vertices = m_closed_vertices;
    const std::vector<Eigen::Vector3i>& triangles = m_closed_triangles;
    // Only the vertices of tetrahedra whose deformed box (every region of a cut one) meets the reach
    // are placed: a large surface is mostly far from the tool.
    const auto& x = m_solver->state();
    std::vector<unsigned char> tet_near(m_model->elements().size(), 0);
    for (std::size_t t = 0; t < m_model->elements().size(); ++t) {
        const isxfem::XfemElement& el = m_model->elements()[t];
        Eigen::AlignedBox3d box;
        box.setEmpty();
        double jump = 0.0;
        for (std::size_t c = 0; c < 4; ++c) {
            box.extend(1e3 * x[el.node[c]]);
            for (unsigned pattern = 0; el.is_cut() && pattern < (1u << el.cuts.size()); ++pattern) // each region's corner
                box.extend(1e3 * el.region_node(c, pattern, x));
            for (const isxfem::ElementCut& cut : el.cuts) jump += 1e3 * x[cut.enriched[c]].norm();
        }
        // For k > 0 a side's field is the linear one plus k gamma-weighted jumps, at most k sum |a|.
        const Eigen::Vector3d pad = Eigen::Vector3d::Constant(m_model->k() * jump);
        tet_near[t] = Eigen::AlignedBox3d(box.min() - pad, box.max() + pad).intersects(reach);
    }
    std::vector<Eigen::Vector3d> position(vertices.size(), Eigen::Vector3d::Constant(INFINITY));
    std::vector<unsigned char> is_near(vertices.size(), 0);
    for (std::size_t v = 0; v < vertices.size(); ++v) {
        if (!tet_near[vertices[v].tet]) continue;
        position[v] = 1e3 * m_solver->position(vertices[v].tet, vertices[v].bary, vertices[v].side);
        if (reach.contains(position[v])) is_near[v] = 1;
    }
    // Each near vertex carries a third of its triangles' area and their area-weighted normal.
    std::vector<Eigen::Vector3d> normal(vertices.size(), Eigen::Vector3d::Zero());
    std::vector<double> area(vertices.size(), 0.0);
    std::vector<Eigen::Vector3i> touching;
    // A crack face whose corners lie within `closed_walls_mm` of their own points across the crack:
    // its walls have not opened. Each corner's gap is measured once (a corner has several faces).
    std::vector<float> gap(closed_walls_mm > 0.0 ? vertices.size() : 0, -1.0f);
    auto closed = [&](const Eigen::Vector3i& t, int cut) {
        for (int c = 0; c < 3; ++c) {
            const auto k = static_cast<std::size_t>(t[c]);
            if (gap[k] < 0.0f) {
                const isxfem::SurfacePoint& v = vertices[k];
                const int j = m_model->elements()[v.tet].cut_index(cut); // < 0 on the crack's front: one point for both walls
                gap[k] = j < 0 ? 0.0f : static_cast<float>((1e3 * m_solver->position(v.tet, v.bary, v.side ^ (1 << j)) - position[k]).norm());
            }
            if (gap[k] >= closed_walls_mm) return false;
        }
        return true;
    };
    for (std::size_t i = 0; i < triangles.size(); ++i) {
        const Eigen::Vector3i& t = triangles[i];
        if (!is_near[static_cast<std::size_t>(t[0])] && !is_near[static_cast<std::size_t>(t[1])] && !is_near[static_cast<std::size_t>(t[2])]) continue;
        for (int c = 0; c < 3; ++c) // a corner outside the tetrahedra near the tool is placed now
            if (!std::isfinite(position[static_cast<std::size_t>(t[c])].x())) {
                const isxfem::SurfacePoint& v = vertices[static_cast<std::size_t>(t[c])];
                position[static_cast<std::size_t>(t[c])] = 1e3 * m_solver->position(v.tet, v.bary, v.side);
            }
        if (closed_walls_mm > 0.0 && m_closed_crack[i] >= 0 && closed(t, m_closed_crack[i])) continue;
        const Eigen::Vector3d n = (position[static_cast<std::size_t>(t[1])] - position[static_cast<std::size_t>(t[0])])
                                      .cross(position[static_cast<std::size_t>(t[2])] - position[static_cast<std::size_t>(t[0])]);
        for (int c = 0; c < 3; ++c) {
            normal[static_cast<std::size_t>(t[c])] += n;
            area[static_cast<std::size_t>(t[c])] += n.norm() / 6.0;
        }
        touching.push_back(t);
    }
    std::vector<int> index(vertices.size(), -1);
    for (std::size_t v = 0; v < vertices.size(); ++v)
        if (is_near[v] && area[v] > 0.0) {
            index[v] = static_cast<int>(out.near.size());
            out.near.push_back(static_cast<std::uint32_t>(v));
            out.positions.push_back(position[v]);
            out.areas.push_back(area[v]);
            out.normals.push_back(normal[v].normalized());
        }
    for (const Eigen::Vector3i& t : touching)
        if (index[static_cast<std::size_t>(t[0])] >= 0 && index[static_cast<std::size_t>(t[1])] >= 0 && index[static_cast<std::size_t>(t[2])] >= 0)
            out.triangles.emplace_back(index[static_cast<std::size_t>(t[0])], index[static_cast<std::size_t>(t[1])], index[static_cast<std::size_t>(t[2])]);
    return out;
}

IsxfemSimulation::Touch IsxfemSimulation::touch(const contact::PlacedShape& tool, const contact::ContactParameters& parameters,
                                                const contact::PlacedShape* from, double closed_walls_mm) const
{
    // Only the surface within the tool's reach (at both poses) is measured, and as far beyond as
    // an edge may reach into it (no edge is longer than two voxels).
    const double edge_reach = parameters.margin_mm + 2.0e3 * m_grid.voxels().voxel_size_m().maxCoeff();
    Eigen::AlignedBox3d reach = tool.world_bounds(edge_reach);
    if (from && from->shape) reach.extend(from->world_bounds(edge_reach));
    const NearSurface s = near_surface(reach, closed_walls_mm);
    Touch out;
    out.contact = contact::penalty_contact(tool, parameters, s.positions, s.areas, s.normals, from && from->shape ? from : nullptr, s.triangles);
    for (const contact::PointContact& c : out.contact.points) {
        const isxfem::SurfacePoint& v = (*s.vertices)[s.near[c.point]];
        out.loads.push_back({v.tet, v.bary, v.side, c.force_n, 1e3 * c.stiffness_matrix_n_per_mm()});
    }
    return out;
}

IsxfemSimulation::ObstacleTouch IsxfemSimulation::touch_obstacle(const contact::Obstacle& obstacle, double dt_s,
                                                                 contact::FrictionAnchors& anchors, double skin_mm, double approach_mm) const
{
    Eigen::AlignedBox3d reach = obstacle.bounds();
    reach.min().array() -= approach_mm;
    reach.max().array() += approach_mm;
    const NearSurface s = near_surface(reach, 0.0);
    // A material point is its rest position (to 1 nm) and side: the same point after a cut.
    std::vector<std::uint64_t> keys;
    std::vector<Eigen::Vector3d> velocities, ends;
    keys.reserve(s.near.size());
    velocities.reserve(s.near.size());
    for (std::size_t i = 0; i < s.near.size(); ++i) {
        const isxfem::SurfacePoint& v = (*s.vertices)[s.near[i]];
        velocities.push_back(1e3 * m_solver->velocity(v.tet, v.bary, v.side));
        ends.push_back(s.positions[i] + free_step_mm(velocities.back(), dt_s));
        std::uint64_t key = static_cast<std::uint64_t>(v.side);
        for (int a = 0; a < 3; ++a)
            key = key * 0x9E3779B97F4A7C15ull + static_cast<std::uint64_t>(std::llround(v.rest_m[a] * 1e9));
        keys.push_back(key);
    }
    ObstacleTouch out;
    out.contact = contact::obstacle_contact(obstacle, s.positions, s.areas, velocities, dt_s, keys, anchors, skin_mm, ends);
    // The push along the normal at the step's end, as a one-sided pair contact; friction as loads.
    for (const contact::PointContact& c : out.contact.points) {
        const isxfem::SurfacePoint& v = (*s.vertices)[s.near[c.point]];
        fem::PairContact pair;
        add_point_terms(v, 1.0, pair.terms);
        pair.normal = c.normal;
        pair.force_n = c.normal_force_n();
        pair.stiffness_n_per_m = 1e3 * c.stiffness_n_per_mm;
        pair.waiting = c.depth_mm <= -skin_mm;
        out.pairs.push_back(std::move(pair));
        if (!c.friction_stiffness_n_per_mm.isZero())
            out.loads.push_back({v.tet, v.bary, v.side, c.across_force_n(), 1e3 * c.friction_stiffness_n_per_mm});
    }
    return out;
}

Eigen::Vector3d IsxfemSimulation::free_step_mm(const Eigen::Vector3d& velocity_mm_s, double dt_s) const
{
    return dt_s * (velocity_mm_s + 1e3 * dt_s * m_gravity);
}

void IsxfemSimulation::add_point_terms(const isxfem::SurfacePoint& v, double weight, std::vector<fem::BlockWeight>& terms) const
{
    const isxfem::XfemElement& el = m_model->elements()[v.tet];
    const auto w = m_solver->weights(v.tet, v.bary, v.side);
    for (std::size_t a = 0; a < el.block_count(); ++a) {
        if (w[a] != 0.0) fem::add_term(terms, el.block(a), weight * w[a]);
    }
}

void IsxfemSimulation::refresh_contact_groups(double cell_mm) const
{
    refresh_closed_surface();
    ContactGroups& g = m_contact_groups;
    if (g.revision == m_closed_revision && g.cell_mm == cell_mm && g.of_vertex.size() == m_closed_vertices.size()) return;
    g.revision = m_closed_revision;
    g.cell_mm = cell_mm;
    g.cell.clear();
    g.holds_cut.clear();
    g.of_vertex.resize(m_closed_vertices.size());
    if (m_closed_vertices.empty()) return;
    // Cells numbered densely over the surface's box at rest: a lookup per vertex, no sort.
    std::vector<Eigen::Array3i> at(m_closed_vertices.size());
    Eigen::Array3i low = Eigen::Array3i::Constant(std::numeric_limits<int>::max()), high = -low;
    for (std::size_t i = 0; i < at.size(); ++i) {
        at[i] = (1e3 * m_closed_vertices[i].rest_m.array() / cell_mm).floor().cast<int>();
        low = low.min(at[i]);
        high = high.max(at[i]);
    }
    // The closed surface's connected parts: each separate piece is closed on its own, and two
    // pieces are never joined, however near they lie at rest.
    UnionFind parts(m_closed_vertices.size());
    for (const Eigen::Vector3i& t : m_closed_triangles) {
        parts.unite(static_cast<std::uint32_t>(t[0]), static_cast<std::uint32_t>(t[1]));
        parts.unite(static_cast<std::uint32_t>(t[0]), static_cast<std::uint32_t>(t[2]));
    }
    g.part.clear();
    const Eigen::Array<std::int64_t, 3, 1> dims = (high - low + 1).cast<std::int64_t>();
    std::vector<std::uint32_t> group_of_cell(static_cast<std::size_t>(dims.prod()), ~0u), next_in_cell;
    for (std::size_t i = 0; i < at.size(); ++i) {
        const Eigen::Array<std::int64_t, 3, 1> c = (at[i] - low).cast<std::int64_t>();
        std::uint32_t& first = group_of_cell[static_cast<std::size_t>((c.z() * dims.y() + c.y()) * dims.x() + c.x())];
        const std::uint32_t part = parts.find(static_cast<std::uint32_t>(i));
        std::uint32_t group = first;
        while (group != ~0u && g.part[group] != part) group = next_in_cell[group];
        if (group == ~0u) {
            group = static_cast<std::uint32_t>(g.cell.size());
            next_in_cell.push_back(first);
            first = group;
            g.cell.push_back(at[i]);
            g.part.push_back(part);
            g.holds_cut.push_back(0);
        }
        g.of_vertex[i] = group;
        if (m_model->elements()[m_closed_vertices[i].tet].is_cut()) g.holds_cut[group] = 1;
    }
}

IsxfemSimulation::PieceTouch IsxfemSimulation::touch_pieces(double dt_s, const contact::PieceContactParameters& parameters) const
{
    refresh_closed_surface();
    const std::vector<isxfem::SurfacePoint>& vertices = m_closed_vertices;
    std::vector<Eigen::Vector3d> start(vertices.size()), end(vertices.size());
    // Every vertex, each frame: on both cores (a liver at level 4 has 58,000).
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, vertices.size(), 1024), [&](const tbb::blocked_range<std::size_t>& range) {
        for (std::size_t i = range.begin(); i != range.end(); ++i) {
            const isxfem::SurfacePoint& v = vertices[i];
            start[i] = 1e3 * m_solver->position(v.tet, v.bary, v.side);
            end[i] = start[i] + free_step_mm(1e3 * m_solver->velocity(v.tet, v.bary, v.side), dt_s);
        }
    });
    // Broad phase, as the branched grid's by elements (cut/piece_contact.hpp): the surface
    // vertices are grouped by cells of four approaches at rest and by piece, each group boxed
    // over its vertices' sweep, and groups are tested in pairs whose boxes come within the
    // approach of each other and that material does not join. Two groups of whole tetrahedra of
    // one piece in neighbouring cells at rest are joined: a piece's surfaces within about two
    // cells of each other at rest count as one material unless a cut passes between them. A
    // group holding a cut tetrahedron holds a crack's two walls, which lie on each other, so it
    // is always tested, and with every group near it. (Grouped by tetrahedron, joined when two
    // share a node, the liver at level 4 passed every vertex on: a coarse tetrahedron's surface,
    // boxed whole, overlaps the boxes of many it does not touch.)
    refresh_contact_groups(4.0 * parameters.approach_mm);
    const ContactGroups& groups = m_contact_groups;
    std::vector<Eigen::AlignedBox3d> boxes(groups.cell.size());
    for (Eigen::AlignedBox3d& box : boxes) box.setEmpty();
    for (std::size_t i = 0; i < vertices.size(); ++i) {
        boxes[groups.of_vertex[i]].extend(start[i]);
        boxes[groups.of_vertex[i]].extend(end[i]);
    }
    for (Eigen::AlignedBox3d& box : boxes) {
        box.min().array() -= 0.5 * parameters.approach_mm;
        box.max().array() += 0.5 * parameters.approach_mm;
    }
    std::vector<unsigned char> kept(groups.holds_cut);
    auto joined = [&](std::uint32_t p, std::uint32_t q) {
        return groups.part[p] == groups.part[q] && !groups.holds_cut[p] && !groups.holds_cut[q] && ((groups.cell[p] - groups.cell[q]).abs() <= 1).all();
    };
    contact::BoxGrid(std::move(boxes), std::max(groups.cell_mm, 1e-6)).overlapping_pairs([&](std::uint32_t p, std::uint32_t q) {
        if (!joined(p, q)) kept[p] = kept[q] = 1;
    });
    // The patch: the kept groups' vertices press; the triangles around them bring their other
    // corners as its rim.
    constexpr std::uint32_t none = ~0u;
    contact::SurfacePatch patch;
    std::vector<std::uint32_t> slots, index(vertices.size(), none);
    auto add = [&](std::uint32_t v, bool presses) {
        if (index[v] == none) {
            index[v] = static_cast<std::uint32_t>(slots.size());
            slots.push_back(v);
            patch.presses.push_back(0);
        }
        if (presses) patch.presses[index[v]] = 1;
    };
    for (std::uint32_t v = 0; v < vertices.size(); ++v)
        if (kept[groups.of_vertex[v]]) add(v, true);
    const std::size_t pressing = slots.size();
    for (const Eigen::Vector3i& t : m_closed_triangles) {
        // The pressing vertices came first (none is larger than any place).
        auto presses = [&](int v) { return index[static_cast<std::size_t>(v)] < pressing; };
        if (!presses(t[0]) && !presses(t[1]) && !presses(t[2])) continue;
        for (int c = 0; c < 3; ++c) add(static_cast<std::uint32_t>(t[c]), false);
        patch.triangles.emplace_back(index[static_cast<std::size_t>(t[0])], index[static_cast<std::size_t>(t[1])], index[static_cast<std::size_t>(t[2])]);
    }
    for (std::uint32_t v : slots) {
        patch.start_mm.push_back(start[v]);
        patch.end_mm.push_back(end[v]);
        patch.rest_mm.push_back(1e3 * vertices[v].rest_m);
    }
    PieceTouch out;
    out.vertices = pressing;
    contact::SurfaceContacts found = contact::surface_contacts(patch, parameters);
    out.faces = std::move(found.faces);
    out.edges = std::move(found.edges);
    auto on_blocks = [&](std::uint32_t i, double w, std::vector<fem::BlockWeight>& terms) { add_point_terms(vertices[slots[i]], w, terms); };
    for (const contact::FaceContact& f : out.faces) out.pairs.push_back(cut::face_pair(f, patch, parameters.skin_mm, on_blocks));
    for (const contact::EdgeContact& e : out.edges) out.pairs.push_back(cut::edge_pair(e, parameters.skin_mm, on_blocks));
    return out;
}

void IsxfemSimulation::sample_surface(const Eigen::AlignedBox3d& box, contact::SurfacePoints& out, double closed_walls_mm) const
{
    const NearSurface s = near_surface(box, closed_walls_mm);
    out.count = std::min(s.positions.size(), out.capacity());
    out.truncated = s.positions.size() > out.capacity();
    std::copy_n(s.positions.begin(), out.count, out.positions_mm.begin());
    std::copy_n(s.normals.begin(), out.count, out.normals.begin());
    std::copy_n(s.areas.begin(), out.count, out.areas_mm2.begin());
    out.triangles.clear();
    for (const Eigen::Vector3i& t : s.triangles)
        if (t.maxCoeff() < static_cast<int>(out.count)) out.triangles.push_back(t);
    out.index();
}

} // namespace vox::sim
