#include "app/isxfem_simulation.hpp"

#include "app/scene_simulation.hpp"
#include "cut/model_surface.hpp"
#include "fem/hex_model.hpp"
#include "fem/rest_cholesky.hpp"

namespace vox::app {

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
    isxfem::XfemOptions o;
    o.dt_s = scene.solver.dt_s;
    o.cg_tolerance = scene.solver.cg_tolerance;
    o.cg_max_iterations = scene.solver.cg_max_iterations;
    o.rayleigh_mass_per_s = scene.solver.rayleigh_mass_per_s;
    o.rayleigh_stiffness_s = scene.solver.rayleigh_stiffness_s;
    m_solver = std::make_unique<isxfem::XfemSolver>(*m_model, o);
    switch (scene.solver.preconditioner) {
    case io::PreconditionerChoice::multigrid:
        throw scene.error("solver.preconditioner", "\"isxfem\" has no multigrid; use \"auto\", \"cholesky\" or \"jacobi\"");
    case io::PreconditionerChoice::jacobi:
        break;
    default: // the warped factor, taken again after each cut and when the object has turned away from it
        m_solver->set_preconditioner(std::make_unique<fem::RestCholesky>(Eigen::Matrix3d::Identity()));
    }
    m_solver->set_gravity(scene.gravity_m_s2);
    for (std::size_t k = 0; k < scene.constraints.size(); ++k) {
        const io::Constraint& c = scene.constraints[k];
        const unsigned axes = (c.held_axes[0] ? 1u : 0u) | (c.held_axes[1] ? 2u : 0u) | (c.held_axes[2] ? 4u : 0u);
        const std::vector<std::uint32_t> nodes = nodes_in_box(grid, hex, level, c.box_min_mm, c.box_max_mm);
        if (nodes.empty())
            throw scene.error("constraints[" + std::to_string(k) + "].box_mm", "catches no node at level " + std::to_string(level));
        for (std::uint32_t n : nodes) m_solver->fix(n, axes);
    }

    // The surface, each used vertex located in a tetrahedron of its element.
    m_surface = std::make_unique<surface::EmbeddedSurface>(grid, std::max(level, 1));
    const cut::ModelSurface embedding(grid, hex, *m_surface);
    for (std::uint32_t v = 0; v < m_surface->vertices().size(); ++v) {
        if (m_surface->vertices()[v].users == 0) continue;
        Embedded e;
        e.rest_m = embedding.vertex_rest_mm(v) * 1e-3;
        e.key = m_surface->vertices()[v].key;
        std::tie(e.tet, e.bary) = isxfem::locate(m_model->mesh(), embedding.vertex_element(v), e.rest_m);
        m_vertices.push_back(e);
    }
}

isxfem::CutReport IsxfemSimulation::cut(const Eigen::Vector3d& point_m, const Eigen::Vector3d& normal,
                                        const std::function<bool(const Eigen::Vector3d&)>& inside, int extend)
{
    const isxfem::CutReport r = m_model->cut(isxfem::PlaneCut{normal, normal.dot(point_m)}, inside, extend);
    if (r.cut_tets > 0) m_solver->model_changed();
    return r;
}

std::vector<Eigen::Vector3d> IsxfemSimulation::surface_displacements() const
{
    std::vector<Eigen::Vector3d> u;
    u.reserve(m_vertices.size());
    for (const Embedded& v : m_vertices) {
        const isxfem::XfemElement& el = m_model->elements()[v.tet];
        double phi = 0.0;
        for (std::size_t c = 0; c < 4; ++c) phi += v.bary[c] * el.phi[c];
        const int side = el.cut >= 0 && phi >= 0.0 ? 1 : 0;
        u.push_back(m_solver->position(v.tet, v.bary, side) - v.rest_m);
    }
    return u;
}

std::vector<std::uint64_t> IsxfemSimulation::surface_keys() const
{
    std::vector<std::uint64_t> keys;
    keys.reserve(m_vertices.size());
    for (const Embedded& v : m_vertices) keys.push_back(v.key);
    return keys;
}

surface::SurfaceMesh IsxfemSimulation::surface_mesh() const
{
    surface::SurfaceMesh out = m_surface->mesh(m_grid); // rest, world mm, the used vertices in slot order
    const std::vector<Eigen::Vector3d> u = surface_displacements();
    // A triangle straddles cut j when one of its vertices lies in a tetrahedron cut by j and its
    // vertices' rest positions lie on both sides of j's plane.
    auto straddles = [&](const Eigen::Vector3i& t) {
        for (int a = 0; a < 3; ++a) {
            const int cut = m_model->elements()[m_vertices[static_cast<std::size_t>(t[a])].tet].cut;
            if (cut < 0) continue;
            const isxfem::PlaneCut& plane = m_model->cut_plane(cut);
            bool negative = false, positive = false;
            for (int b = 0; b < 3; ++b) (plane.at(m_vertices[static_cast<std::size_t>(t[b])].rest_m) < 0.0 ? negative : positive) = true;
            if (negative && positive) return true;
        }
        return false;
    };
    std::erase_if(out.triangles, straddles);
    for (std::size_t k = 0; k < out.positions.size(); ++k) out.positions[k] += 1e3 * u[k];
    return out;
}

} // namespace vox::app
