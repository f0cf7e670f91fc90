#include "sim/dbg_simulation.hpp"

#include "shape/shape_matching.hpp"

#include "cut/pieces.hpp"
#include "cut/state_transfer.hpp"
#include "io/box.hpp"
#include "sim/rigid_parts.hpp"
#include "fem/multigrid.hpp"
#include "fem/rest_cholesky.hpp"

#include "core/stopwatch.hpp"

#include <algorithm>
#include <bit>
#include <stdexcept>

namespace vox::sim {
namespace {

/// Above this many degrees of freedom a sparse factor costs more than it saves (measured on the
/// liver: at level 3, 29 k DOFs, the factor's solves make each step 2.4 times slower than Jacobi).
constexpr std::size_t k_cholesky_dofs = 20000;

fem::SolverOptions solver_options(const io::SolverSettings& s)
{
    fem::SolverOptions o;
    o.dt_s = s.dt_s;
    o.cg_tolerance = s.cg_tolerance;
    o.cg_max_iterations = s.cg_max_iterations;
    o.rayleigh_mass_per_s = s.rayleigh_mass_per_s;
    o.rayleigh_stiffness_s = s.rayleigh_stiffness_s;
    o.quasi_static = s.mode == io::SolverMode::static_equilibrium;
    o.newton_max_iterations = s.newton_max_iterations;
    o.lumped_mass = s.lumped_mass;
    return o;
}

shape::Settings shape_settings(const io::SolverSettings& s)
{
    shape::Settings o;
    o.coarse_levels = s.sm_cluster_levels;
    o.adaptive = s.sm_adaptive;
    o.global_step = s.sm_global_step;
    o.max_iterations = s.sm_max_iterations;
    o.termination_rate = s.sm_termination_rate;
    o.subdivision_strain = s.sm_subdivision_strain;
    return o;
}

/// "auto": a factor when it is small, the multigrid when a coarser level exists, else Jacobi
/// (matrix-free). Jacobi alone is fast per iteration but needs hundreds of them wherever bending
/// or small partial elements spread the spectrum (a 200 x 10 x 10 mm soft beam at level 1, dynamic:
/// 200 iterations leave 18 % of the residual; the warped factor converges in 5 to 8).
io::PreconditionerChoice resolve(io::PreconditionerChoice choice, std::size_t dofs, bool coarser_level)
{
    if (choice != io::PreconditionerChoice::automatic) return choice;
    if (dofs <= k_cholesky_dofs) return io::PreconditionerChoice::cholesky;
    return coarser_level ? io::PreconditionerChoice::multigrid : io::PreconditionerChoice::jacobi;
}

/// Per grid element of `level`: 1 when the change `report` created or updated it.
std::vector<unsigned char> changed_elements(const grid::BranchedGrid& grid, int level, const grid::UpdateReport& report)
{
    std::vector<unsigned char> changed(grid.level(level).elements.size(), 0);
    if (static_cast<std::size_t>(level) < report.levels.size()) {
        const grid::LevelChange& c = report.levels[static_cast<std::size_t>(level)];
        for (const auto& [e, from] : c.created) changed[e] = 1;
        for (std::uint32_t e : c.updated) changed[e] = 1;
    }
    return changed;
}

} // namespace

bool wants_multigrid(const io::Scene& scene, const grid::BranchedGrid& grid, int level)
{
    // The DOF count of a level is three per node; level 0 has about one node per voxel.
    const std::size_t dofs = 3 * (level >= 1 ? grid.level(level).stats.nodes : grid.voxels().alive_count());
    return resolve(scene.solver.preconditioner, dofs, true) == io::PreconditionerChoice::multigrid;
}

grid::BranchedGrid build_scene_grid(const io::Scene& scene, const grid::LabelGrid& labels, int max_level)
{
    const io::MaterialTable table = io::material_table(scene);
    return grid::BranchedGrid(grid::FineVoxels(labels, [&](std::int32_t l) { return table.index_of(l); }), table.materials,
                              max_level);
}

void smooth_scene_surface(const io::Scene& scene, const grid::BranchedGrid& grid, surface::EmbeddedSurface& surface)
{
    if (!io::smooths_surface(scene.object, scene.solver.type)) return;
    surface.smooth_windowed_sinc(grid, k_smoothing_iterations, k_smoothing_passband);
}

DbgSimulation::DbgSimulation(const io::Scene& scene, const grid::BranchedGrid& grid, int level)
    : m_scene(scene), m_grid(&grid), m_rigid_material(rigid_materials(scene)),
      m_level(scene.object.mixed_levels ? scene.object.mixed_levels->fine : level)
{
    if (scene.object.mixed_levels) {
        m_region = starting_region(scene, grid);
        m_mixed = mixed_levels(grid, *scene.object.mixed_levels, m_region);
    }
    build(Build::first);
    m_surface = std::make_unique<surface::EmbeddedSurface>(grid, std::max(m_level, 1)); // two levels: the fine one
    smooth_scene_surface(scene, grid, *m_surface);
    m_model_surface = std::make_unique<cut::ModelSurface>(grid, *m_model, *m_surface);
}

DbgSimulation::DbgSimulation(DbgSimulation& from, int level, io::PreconditionerChoice preconditioner)
    : m_scene(from.m_scene), m_grid(from.m_grid), m_rigid_material(from.m_rigid_material), m_held_voxels(from.m_held_voxels),
      m_held_pieces(from.m_held_pieces), m_level(level)
{
    if (level < 1 || from.m_level < 1) throw std::invalid_argument("DbgSimulation: levels change between 1 and the grid's coarsest");
    m_scene.solver.preconditioner = preconditioner;
    build(Build::level_change);
    cut::transfer_between_levels(*m_grid, *from.m_model, *from.m_solver, *m_model, *m_solver);
    rest_held_nodes();
    m_surface = std::move(from.m_surface);
    m_surface->reembed(*m_grid, level);
    m_model_surface = std::make_unique<cut::ModelSurface>(*m_grid, *m_model, *m_surface);
}

void DbgSimulation::rest_held_nodes()
{
    fem::ImplicitSolver& solver = *m_solver;
    for (std::uint32_t n = 0; n < m_model->node_count(); ++n) {
        if (m_body_of_node[n] >= 0) continue;
        for (int a = 0; a < 3; ++a)
            if (solver.held_axis(n, a)) {
                solver.positions()[n][a] = m_model->rest_positions()[n][a];
                solver.velocities()[n][a] = 0.0;
            }
    }
}

bool DbgSimulation::follow_tools(std::span<const Eigen::AlignedBox3d> reach_mm)
{
    if (!m_mixed || reach_mm.empty()) return false;
    RegionCells cells = followed_region(*m_grid, *m_model, m_solver->positions(), reach_mm, m_region);
    if (cells == m_region) return false;
    set_region(std::move(cells));
    return true;
}

void DbgSimulation::set_region(RegionCells cells)
{
    if (!m_mixed || cells == m_region) return;
    m_region = std::move(cells);
    m_mixed = mixed_levels(*m_grid, *m_scene.object.mixed_levels, m_region);
    std::unique_ptr<fem::HexModel> old_model = std::move(m_model);
    std::unique_ptr<fem::ImplicitSolver> old_solver = std::move(m_solver);
    m_model_surface.reset(); // it refers to the old model
    build(Build::region, old_model.get());
    cut::transfer_between_levels(*m_grid, *old_model, *old_solver, *m_model, *m_solver);
    rest_held_nodes();
    m_model_surface = std::make_unique<cut::ModelSurface>(*m_grid, *m_model, *m_surface);
}

CutTimings DbgSimulation::apply_cut(grid::BranchedGrid& grid, std::span<const grid::Coord> removed,
                                      std::span<const std::pair<grid::Coord, int>> faces)
{
    if (&grid != m_grid) throw std::invalid_argument("DbgSimulation::apply_cut: not the grid it was built on");
    CutTimings t;
    Stopwatch clock;
    const grid::UpdateReport report = grid.update(removed, faces);
    t.grid_update_ms = clock.lap();
    m_surface->update(grid, removed, faces, report);
    t.remesh_ms = clock.lap();
    std::unique_ptr<fem::HexModel> old_model = std::move(m_model);
    std::unique_ptr<fem::ImplicitSolver> old_solver = std::move(m_solver);
    m_model_surface.reset(); // it refers to the old model
    if (m_mixed) m_mixed = mixed_levels(grid, *m_scene.object.mixed_levels, m_region); // on the grid's new elements
    const io::PreconditionerChoice old_choice = m_choice;
    build(Build::cut, old_model.get(), &report, old_solver.get());
    cut::transfer_state(report, *old_model, *old_solver, *m_model, *m_solver);
    const std::vector<std::uint32_t>& old_nodes = old_model->grid_node();
    const std::vector<std::uint32_t>& new_nodes = m_model->grid_node();
    if (m_choice == io::PreconditionerChoice::cholesky && old_choice == m_choice && m_level >= 1 && new_nodes.size() >= old_nodes.size() &&
        std::equal(old_nodes.begin(), old_nodes.end(), new_nodes.begin())) {
        // Every node kept its number (new ones come after them): the factor goes on, corrected for
        // the rows that changed, the nodes of the elements changed before and after the cut (one
        // whose material went entirely is among the old ones only), and over the new nodes
        // (fem/rest_cholesky.hpp).
        const std::vector<unsigned char> changed = changed_elements(grid, m_level, report);
        std::vector<unsigned char> changed_before; // per element of the grid before the cut
        const auto mark = [&](std::uint32_t e) {
            if (e >= changed_before.size()) changed_before.resize(e + 1, 0);
            changed_before[e] = 1;
        };
        if (static_cast<std::size_t>(m_level) < report.levels.size()) {
            const grid::LevelChange& c = report.levels[static_cast<std::size_t>(m_level)];
            for (const std::uint32_t e : c.removed) mark(e);
            for (const std::uint32_t e : c.updated) mark(e);
            for (const auto& [e, from] : c.created)
                for (const std::uint32_t f : from) mark(f);
        }
        std::vector<std::uint32_t> nodes;
        for (const fem::HexElement& el : old_model->elements())
            if (el.grid_element < changed_before.size() && changed_before[el.grid_element]) nodes.insert(nodes.end(), el.dof_node.begin(), el.dof_node.end());
        for (const fem::HexElement& el : m_model->elements())
            if (changed[el.grid_element]) nodes.insert(nodes.end(), el.dof_node.begin(), el.dof_node.end());
        std::sort(nodes.begin(), nodes.end());
        nodes.erase(std::unique(nodes.begin(), nodes.end()), nodes.end());
        m_solver->adopt_preconditioner(*old_solver, nodes);
    }
    m_model_surface = std::make_unique<cut::ModelSurface>(grid, *m_model, *m_surface);
    old_solver.reset(); // freeing the old factor is part of the update (it took milliseconds unseen)
    old_model.reset();
    t.fem_update_ms = clock.lap();
    return t;
}

void DbgSimulation::find_pieces(const std::vector<std::uint32_t>& piece)
{
    const fem::HexModel& model = *m_model;
    fem::ImplicitSolver& solver = *m_solver;
    m_pieces.clear();
    m_solver_asleep.assign(model.node_count(), 0);
    const std::size_t count = piece.empty() ? 0 : *std::max_element(piece.begin(), piece.end()) + 1;
    m_pieces.resize(count);
    std::vector<unsigned char> listed(model.node_count(), 0), plastic(count, 0);
    const std::vector<io::Material> materials = io::material_table(m_scene).scene_materials;
    for (std::uint32_t e = 0; e < model.elements().size(); ++e) {
        Piece& p = m_pieces[piece[e]];
        for (std::uint32_t n : model.elements()[e].dof_node)
            if (!listed[n]++) p.nodes.push_back(n);
        const auto material = static_cast<std::size_t>(model.elements()[e].material);
        if (material < materials.size() && materials[material].plasticity) plastic[piece[e]] = 1;
    }
    if (m_scene.solver.mode != io::SolverMode::dynamic) return; // a static frame is at rest already
    for (std::size_t k = 0; k < count; ++k) {
        Piece& p = m_pieces[k];
        bool free = false, loaded = false, body = false;
        for (std::uint32_t n : p.nodes) {
            free = free || !solver.held(n);
            loaded = loaded || solver.external_forces()[n].squaredNorm() > 0.0;
            body = body || m_body_of_node[n] >= 0;
        }
        p.free = free;
        p.can_sleep = free && !loaded && !body && !plastic[k];
    }
}

bool DbgSimulation::all_asleep() const
{
    return m_bodies.empty() && std::any_of(m_pieces.begin(), m_pieces.end(), [](const Piece& p) { return p.asleep; }) &&
           std::all_of(m_pieces.begin(), m_pieces.end(), [](const Piece& p) { return p.asleep || !p.free; });
}

void DbgSimulation::apply_sleep()
{
    // When everything that could move sleeps, the solve is skipped whole and the solver keeps the
    // holds it was built with: waking then takes no new factor (the common case: one object left
    // alone, then touched again). Otherwise the sleeping pieces are held in the solve.
    std::vector<unsigned char> asleep(m_model->node_count(), 0);
    if (!all_asleep())
        for (const Piece& p : m_pieces)
            if (p.asleep)
                for (std::uint32_t n : p.nodes) asleep[n] = 1;
    if (asleep == m_solver_asleep) return;
    m_solver->set_asleep(asleep);
    m_solver_asleep = std::move(asleep);
}

std::size_t DbgSimulation::asleep_piece_count() const
{
    return static_cast<std::size_t>(std::count_if(m_pieces.begin(), m_pieces.end(), [](const Piece& p) { return p.asleep; }));
}

fem::StepStats DbgSimulation::step()
{
    const auto near_tool = [&](const Eigen::AlignedBox3d& box) {
        return std::any_of(m_tool_reach.begin(), m_tool_reach.end(), [&](const Eigen::AlignedBox3d& t) { return t.intersects(box); });
    };
    bool changed = false;
    for (Piece& p : m_pieces)
        if (p.asleep && near_tool(p.box_mm)) {
            p.asleep = false;
            p.rest_s = 0.0;
            changed = true;
        }
    if (changed) apply_sleep();
    fem::StepStats s;
    if (all_asleep()) { // nothing to step: the object is at rest and still
        Stopwatch clock;
        for (Eigen::Vector3d& v : m_solver->velocities()) v.setZero();
        s.elastic_energy_j = m_resting.elastic_energy_j;
        s.max_displacement_m = m_resting.max_displacement_m;
        s.step_ms = clock.lap();
    } else {
        s = m_resting = step_awake();
    }
    // Pieces that came to rest fall asleep.
    fem::ImplicitSolver& solver = *m_solver;
    std::vector<unsigned char> touched(m_model->node_count(), 0);
    for (const fem::NodeContact& c : solver.contact()) touched[c.node] = 1;
    changed = false;
    for (Piece& p : m_pieces) {
        if (!p.can_sleep || p.asleep) continue;
        Eigen::AlignedBox3d box;
        box.setEmpty();
        bool resting = true;
        for (std::uint32_t n : p.nodes) {
            resting = resting && !touched[n] && solver.velocities()[n].norm() < k_sleep_speed_m_s;
            box.extend(solver.positions()[n] * 1e3);
        }
        p.rest_s = resting && !near_tool(box) ? p.rest_s + m_scene.solver.dt_s : 0.0;
        if (p.rest_s + 1e-9 < k_sleep_after_s) continue;
        p.asleep = true;
        p.box_mm = box;
        changed = true;
    }
    if (changed) apply_sleep();
    return s;
}

fem::StepStats DbgSimulation::step_awake()
{
    if (m_bodies.empty()) return m_solver->step();
    // The bodies' state from their nodes, which then stand still in the finite-element solve
    // (they are held there, and a held node's velocity would count as energy the step lost).
    Stopwatch clock;
    fem::ImplicitSolver& solver = *m_solver;
    std::vector<fem::RigidBody::State> states;
    for (const fem::RigidBody& b : m_bodies) {
        states.push_back(b.state(solver.positions(), solver.velocities()));
        for (std::uint32_t n : b.nodes()) solver.velocities()[n].setZero();
    }
    fem::StepStats s = solver.step();
    const double damping = m_scene.solver.rayleigh_mass_per_s;
    for (std::size_t k = 0; k < m_bodies.size(); ++k) {
        const fem::RigidBody::State next =
            m_bodies[k].advance(states[k], m_scene.solver.dt_s, damping, m_scene.gravity_m_s2, solver.external_forces(), solver.contact(),
                                m_body_of_node, static_cast<std::int32_t>(k), solver.positions(), solver.velocities());
        s.kinetic_energy_j += m_bodies[k].kinetic_energy(next);
        for (std::uint32_t n : m_bodies[k].nodes())
            s.max_displacement_m = std::max(s.max_displacement_m, (solver.positions()[n] - m_model->rest_positions()[n]).norm());
    }
    s.step_ms = clock.lap();
    return s;
}

void DbgSimulation::build(Build kind, const fem::HexModel* previous, const grid::UpdateReport* report,
                          const fem::ImplicitSolver* previous_solver)
{
    const io::Scene& scene = m_scene;
    const grid::BranchedGrid& grid = *m_grid;
    const int level = m_level;
    std::vector<unsigned char> changed, changed_coarse; // per grid element of the level (and the coarse one): touched by the cut
    if (previous && report && level >= 1) {
        changed = changed_elements(grid, level, *report);
        if (m_mixed) changed_coarse = changed_elements(grid, m_mixed->coarse(), *report);
    }
    if (m_mixed) {
        // After a cut the elements it changed are evaluated again; after a move of the region, the
        // elements new to the model.
        m_model = std::make_unique<fem::HexModel>(grid, *m_mixed, previous,
                                                  std::array<const std::vector<unsigned char>*, 2>{report ? &changed : nullptr, report ? &changed_coarse : nullptr});
    } else if (previous && level >= 1) {
        // The elements the change touched; all others keep their matrices.
        m_model = std::make_unique<fem::HexModel>(grid, level, *previous, changed);
    } else {
        m_model = std::make_unique<fem::HexModel>(grid, level);
    }
    const fem::HexModel& model = *m_model;

    // Which axes of which nodes are held, before the solver exists: the preconditioner is chosen
    // by the degrees of freedom left free (a rigid skull leaves none).
    // The material each box holds: measured afresh, or after a cut in the elements it changed.
    // A move of the fine region keeps the grid, and so what the boxes hold.
    const bool after_cut = kind == Build::cut && previous && level >= 1 && !m_boxes.empty();
    if (kind != Build::region && !after_cut) {
        m_boxes.clear();
        for (const io::Constraint& c : scene.constraints) m_boxes.emplace_back(c.box_min_mm, c.box_max_mm);
        for (const io::Load& l : scene.loads) m_boxes.emplace_back(l.box_min_mm, l.box_max_mm);
    }
    for (BoxMaterial& b : m_boxes) {
        if (kind == Build::region) continue; // measured already
        b.update(grid, level, after_cut ? &changed : nullptr);
        if (m_mixed) b.update(grid, m_mixed->coarse(), after_cut ? &changed_coarse : nullptr);
    }
    std::vector<unsigned> held_axes(model.node_count(), 0u);
    std::vector<unsigned char> constrained(model.node_count(), 0);
    for (std::size_t k = 0; k < scene.constraints.size(); ++k) {
        const io::Constraint& c = scene.constraints[k];
        const unsigned axes = (c.held_axes[0] ? 1u : 0u) | (c.held_axes[1] ? 2u : 0u) | (c.held_axes[2] ? 4u : 0u);
        const std::vector<std::uint32_t> nodes = m_boxes[k].supported_nodes(model);
        for (std::uint32_t n : nodes) {
            held_axes[n] |= axes;
            constrained[n] = 1;
        }
        if (nodes.empty() && (kind == Build::first || kind == Build::level_change))
            throw scene.error("constraints[" + std::to_string(k) + "].box_mm", "holds no voxel centre of the object");
    }
    // Rigid material holds the soft material of its piece, so "hold" leaves such pieces to it.
    const std::vector<std::uint32_t> piece = cut::element_pieces(model);
    const std::vector<RigidContent> rigid_element = rigid_content(grid, model, m_rigid_material);
    if (scene.object.unheld == io::UnheldPieces::hold)
        hold_unheld_pieces(kind == Build::first, anchoring_nodes(model, piece, rigid_element, constrained), held_axes);
    std::vector<unsigned char> held(model.node_count(), 0);
    for (std::uint32_t n = 0; n < model.node_count(); ++n) held[n] = held_axes[n] != 0u;
    const RigidParts rigid = rigid_parts(model, piece, rigid_element, held, scene.object.unheld == io::UnheldPieces::rigid);
    m_rigid_elements = rigid.rigid_elements;
    m_bodies.clear();
    m_body_of_node.assign(model.node_count(), -1);
    for (const std::vector<std::uint32_t>& nodes : rigid.bodies) {
        for (std::uint32_t n : nodes) {
            held_axes[n] = 7u; // placed by the body's own step
            m_body_of_node[n] = static_cast<std::int32_t>(m_bodies.size());
        }
        m_bodies.emplace_back(nodes, model.rest_positions(), model.nodal_mass());
    }
    std::size_t free_dofs = 0;
    for (std::uint32_t n = 0; n < model.node_count(); ++n) {
        if (rigid.anchored[n]) held_axes[n] = 7u;
        free_dofs += 3 - static_cast<std::size_t>(std::popcount(held_axes[n]));
    }

    // Two levels: Jacobi on the free space (a factor of the whole matrix restricted to it does no
    // better, docs/branched-grid.md).
    const io::PreconditionerChoice choice = m_choice = free_dofs == 0 || m_mixed ? io::PreconditionerChoice::jacobi
                                                           : resolve(scene.solver.preconditioner, free_dofs, level < grid.max_level());
    if (choice == io::PreconditionerChoice::multigrid && level >= grid.max_level())
        throw scene.error("solver.preconditioner", "multigrid needs a level coarser than the simulated one");
    fem::SolverOptions options = solver_options(scene.solver);
    const bool shape_matching = scene.solver.type == io::SolverType::shape_matching;
    options.matrix_free = shape_matching || choice == io::PreconditionerChoice::jacobi;
    m_solver = std::make_unique<fem::ImplicitSolver>(model, options, previous_solver);
    fem::ImplicitSolver& solver = *m_solver;
    for (std::uint32_t n = 0; n < model.node_count(); ++n)
        if (held_axes[n]) solver.fix(n, held_axes[n]);
    if (shape_matching) {
        auto integrator = std::make_unique<shape::ShapeMatching>(grid, model, shape_settings(scene.solver));
        m_linear_solver = integrator->description();
        solver.set_integrator(std::move(integrator));
    } else switch (choice) {
    case io::PreconditionerChoice::cholesky:
        solver.set_preconditioner(std::make_unique<fem::RestCholesky>(model.frame(), 25, fem::RestCholesky::background_flops_here()));
        m_linear_solver = "CG, warped Cholesky preconditioner";
        break;
    case io::PreconditionerChoice::multigrid: {
        auto mg = std::make_unique<fem::Multigrid>(grid, model, grid.max_level());
        m_linear_solver = "CG, multigrid preconditioner (" + std::to_string(mg->level_count()) + " levels)";
        solver.set_preconditioner(std::move(mg));
        break;
    }
    default:
        m_linear_solver = free_dofs == 0 ? "none: every node is held or rigid" : "CG, Jacobi preconditioner, matrix-free";
    }

    std::vector<fem::MaterialBehaviour> behaviour;
    for (const io::Material& m : io::material_table(scene).scene_materials) {
        fem::MaterialBehaviour b;
        if (m.plasticity) {
            b.yield_strain = m.plasticity->yield_strain;
            b.creep_per_s = m.plasticity->creep_per_s;
            b.max_strain = m.plasticity->max_strain;
        }
        b.wet_stiffness_ratio = m.wetting.stiffness_ratio;
        b.wet_yield_ratio = m.wetting.yield_ratio;
        behaviour.push_back(b);
    }
    solver.set_materials(std::move(behaviour));
    for (std::size_t k = 0; kind == Build::first && k < scene.wet_regions.size(); ++k) {
        const io::WetRegion& w = scene.wet_regions[k];
        bool caught = false;
        for (std::uint32_t e = 0; e < model.elements().size(); ++e)
            if (io::in_box(model.elements()[e].centroid * 1e3, w.box_min_mm, w.box_max_mm)) {
                solver.set_water(e, w.water);
                caught = true;
            }
        if (!caught)
            throw scene.error("wet_regions[" + std::to_string(k) + "].box_mm",
                              "holds the material centre of no element at level " + std::to_string(level));
    }

    solver.set_gravity(scene.gravity_m_s2);
    for (std::size_t k = 0; k < scene.loads.size(); ++k) {
        const io::Load& load = scene.loads[k];
        const BoxMaterial& box = m_boxes[scene.constraints.size() + k];
        const bool empty = box.voxel_count(model) == 0;
        if (empty && (kind == Build::cut || kind == Build::region)) continue; // the cut took the loaded material
        if (empty) throw scene.error("loads[" + std::to_string(k) + "].box_mm", "holds no voxel centre of the object");
        for (const auto& [n, share] : box.load_shares(model)) solver.external_forces()[n] += share * load.force_n;
    }
    find_pieces(piece);
}

void DbgSimulation::hold_unheld_pieces(bool first, const std::vector<unsigned char>& constrained, std::vector<unsigned>& held_axes)
{
    const fem::HexModel& model = *m_model;
    const grid::BranchedGrid& grid = *m_grid;
    // The fine voxels of model element e (level 0: the element is one voxel).
    const auto first_voxel = [&](std::uint32_t e) {
        const fem::HexElement& el = model.elements()[e];
        return el.level == 0 ? el.grid_element : grid.level(el.level).elements[el.grid_element].voxels.front();
    };
    if (first) {
        // The pieces as the run starts; their voxels stay held through later cuts and rebuilds,
        // while pieces a cut frees from held material fall.
        const std::vector<unsigned char> unheld = cut::unheld_elements(model, constrained, m_held_pieces);
        m_held_voxels.assign(grid.voxels().slots(), 0);
        for (std::uint32_t e = 0; e < model.elements().size(); ++e) {
            if (!unheld[e]) continue;
            const fem::HexElement& el = model.elements()[e];
            if (el.level == 0) {
                m_held_voxels[el.grid_element] = 1;
            } else {
                for (std::uint32_t v : grid.level(el.level).elements[el.grid_element].voxels) m_held_voxels[v] = 1;
            }
        }
    }
    if (m_held_pieces == 0) return;
    // An element's material is connected, so its first voxel says for all of them.
    for (std::uint32_t e = 0; e < model.elements().size(); ++e)
        if (m_held_voxels[first_voxel(e)])
            for (std::uint32_t n : model.elements()[e].dof_node) held_axes[n] = 7u;
}

} // namespace vox::sim
