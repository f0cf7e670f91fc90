#include "fem/implicit_solver.hpp"

#include "fem/conjugate_gradient.hpp"

#include "core/error.hpp"
#include "fem/corotation.hpp"
#include "fem/element_kernel.hpp"
#include "fem/node_integrator.hpp"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <utility>

namespace vox::fem {

void SolverOptions::validate() const
{
    auto bad = [](const std::string& what) { throw InputError("solver: " + what); };
    if (!(dt_s > 0.0) || !std::isfinite(dt_s)) bad("dt_s must be positive, got " + std::to_string(dt_s));
    if (!(cg_tolerance > 0.0 && cg_tolerance < 1.0)) bad("cg_tolerance must be in (0, 1)");
    if (cg_max_iterations < 1) bad("cg_max_iterations must be at least 1");
    if (!(rayleigh_mass_per_s >= 0.0) || !(rayleigh_stiffness_s >= 0.0)) bad("Rayleigh damping must not be negative");
    if (newton_max_iterations < 1) bad("newton_max_iterations must be at least 1");
}

ImplicitSolver::ImplicitSolver(const HexModel& model, const SolverOptions& options, const ImplicitSolver* same_mesh)
    : m_model(model), m_options(options)
{
    m_options.validate();
    const std::size_t n = model.node_count();
    m_x = model.rest_positions();
    m_v.assign(n, Eigen::Vector3d::Zero());
    m_external.assign(n, Eigen::Vector3d::Zero());
    m_fixed.assign(3 * n, 0);
    m_held.assign(3 * n, 0);
    m_contact_of_node.assign(n, -1);
    m_rotation.assign(model.elements().size(), Eigen::Quaterniond::Identity());
    m_node_rotation.assign(n, Eigen::Quaterniond::Identity());
    m_element_energy.assign(model.elements().size(), 0.0);
    m_stiffness_scale.assign(model.elements().size(), 1.0);
    m_behaviour.resize(model.materials().size());
    m_element_rotation.assign(model.elements().size(), Eigen::Matrix3d::Identity());
    m_volume_hessian.assign(model.elements().size(), VolumeHessian{});
    m_squeezed.assign(model.elements().size(), 0);
    m_internal = Eigen::VectorXd::Zero(static_cast<Eigen::Index>(3 * n));
    if (same_mesh && same_mesh->m_options.matrix_free == m_options.matrix_free && same_connectivity(same_mesh->m_model, model)) {
        // A cut that changed element matrices only (a drill taking a voxel a frame): the
        // incidence and the matrix pattern are those of the previous solver.
        m_incidence_start = same_mesh->m_incidence_start;
        m_incidence = same_mesh->m_incidence;
        m_rank = same_mesh->m_rank;
        m_diagonal_rank = same_mesh->m_diagonal_rank;
        m_run_groups = same_mesh->m_run_groups;
        m_matrix = same_mesh->m_matrix;
        std::fill(m_matrix.valuePtr(), m_matrix.valuePtr() + m_matrix.nonZeros(), 0.0);
        return;
    }
    build_pattern();
}

namespace {
/// Elements per run of the matrix-free product: consecutive elements lie close together (the
/// branched grid numbers them along its octree), so a run's nodes stay in cache while it adds
/// into them.
constexpr std::size_t k_product_run = 64;
} // namespace

void ImplicitSolver::group_runs()
{
    const auto& elements = m_model.elements();
    const std::size_t runs = (elements.size() + k_product_run - 1) / k_product_run;
    std::vector<std::int32_t> group_of(runs, -1);
    std::vector<std::size_t> seen_by; // per group: the last run that found it beside itself, plus one
    m_run_groups.clear();
    for (std::size_t run = 0; run < runs; ++run) {
        const std::size_t end = std::min(elements.size(), (run + 1) * k_product_run);
        for (std::size_t e = run * k_product_run; e < end; ++e)
            for (std::uint32_t node : elements[e].dof_node)
                for (std::uint32_t k = m_incidence_start[node]; k < m_incidence_start[node + 1]; ++k)
                    if (const std::int32_t g = group_of[m_incidence[k] / 8 / k_product_run]; g >= 0) seen_by[static_cast<std::size_t>(g)] = run + 1;
        std::size_t g = 0;
        while (g < m_run_groups.size() && seen_by[g] == run + 1) ++g;
        if (g == m_run_groups.size()) {
            m_run_groups.emplace_back();
            seen_by.push_back(0);
        }
        m_run_groups[g].push_back(static_cast<std::uint32_t>(run));
        group_of[run] = static_cast<std::int32_t>(g);
    }
}

namespace {
/// A batch function for for_each_element_by_runs that calls f on each element of the batch.
template <typename F>
auto each_element(F&& f)
{
    return [&f](const std::array<std::size_t, 4>& batch, int count) {
        for (int i = 0; i < count; ++i) f(batch[static_cast<std::size_t>(i)]);
    };
}
} // namespace

template <typename F>
void ImplicitSolver::for_each_element_by_runs(F&& f) const
{
    const std::size_t count = m_model.elements().size();
    for (const std::vector<std::uint32_t>& group : m_run_groups)
        tbb::parallel_for(tbb::blocked_range<std::size_t>(0, group.size(), 1), [&](const tbb::blocked_range<std::size_t>& range) {
            for (std::size_t i = range.begin(); i != range.end(); ++i) {
                const std::size_t first = group[i] * k_product_run, end = std::min(count, first + k_product_run);
                std::array<std::size_t, 4> batch{};
                int size = 0;
                for (std::size_t e = first; e < end; ++e)
                    if (m_active[e]) {
                        batch[static_cast<std::size_t>(size++)] = e;
                        if (size == 4) f(batch, std::exchange(size, 0));
                    }
                if (size > 0) f(batch, size);
            }
        });
}

bool ImplicitSolver::same_connectivity(const HexModel& a, const HexModel& b)
{
    if (a.node_count() != b.node_count() || a.elements().size() != b.elements().size()) return false;
    for (std::size_t e = 0; e < a.elements().size(); ++e)
        if (a.elements()[e].dof_node != b.elements()[e].dof_node) return false;
    return true;
}

void ImplicitSolver::build_pattern()
{
    const HexModel& model = m_model;
    const std::size_t n = model.node_count();
    // Which (element, corner) pairs touch each node: the row-wise assembly gathers from them.
    m_incidence_start.assign(n + 1, 0);
    for (const HexElement& e : model.elements())
        for (std::uint32_t node : e.dof_node) ++m_incidence_start[node + 1];
    for (std::size_t i = 0; i < n; ++i) m_incidence_start[i + 1] += m_incidence_start[i];
    m_incidence.resize(m_incidence_start.back());
    std::vector<std::uint32_t> fill(m_incidence_start.begin(), m_incidence_start.end() - 1);
    for (std::uint32_t e = 0; e < model.elements().size(); ++e)
        for (std::uint32_t c = 0; c < 8; ++c) m_incidence[fill[model.elements()[e].dof_node[c]]++] = 8 * e + c;
    group_runs();
    if (m_options.matrix_free) return; // no matrix

    // The matrix pattern: a 3 x 3 block for every pair of nodes sharing an element. Built from
    // each node's sorted neighbour list (never from triplets: on the liver at level 1 those
    // would be 235 million). Node a's three rows hold the same columns, so an entry's position
    // is outer[3a] + i * row_length + 3 * rank + j, rank being b's place among a's neighbours;
    // each element keeps the ranks of its 64 corner pairs. A node's neighbours are gathered from
    // its elements each once (a stamp per node, not a sort of the 64 corners of its 8 elements with
    // their repeats), then sorted, and each one's place read back through a per-node array into
    // the incident elements' ranks. (A sort of the corners and binary searches for the ranks took
    // 2.6 ms on the liver at level 4 in every cutting frame that changed the connectivity.)
    std::vector<std::uint32_t> neighbour_start(n + 1, 0), neighbours;
    m_rank.resize(model.elements().size() * 64);
    m_diagonal_rank.resize(n);
    {
        std::vector<std::uint32_t> stamp(n, ~0u), place(n, 0);
        for (std::uint32_t a = 0; a < n; ++a) {
            const std::size_t begin = neighbours.size();
            for (std::uint32_t k = m_incidence_start[a]; k < m_incidence_start[a + 1]; ++k)
                for (std::uint32_t b : model.elements()[m_incidence[k] / 8].dof_node)
                    if (stamp[b] != a) {
                        stamp[b] = a;
                        neighbours.push_back(b);
                    }
            std::sort(neighbours.begin() + static_cast<std::ptrdiff_t>(begin), neighbours.end());
            neighbour_start[a + 1] = static_cast<std::uint32_t>(neighbours.size());
            for (std::size_t r = begin; r < neighbours.size(); ++r) place[neighbours[r]] = static_cast<std::uint32_t>(r - begin);
            m_diagonal_rank[a] = static_cast<std::uint16_t>(place[a]);
            for (std::uint32_t k = m_incidence_start[a]; k < m_incidence_start[a + 1]; ++k) {
                const std::uint32_t e = m_incidence[k] / 8, c = m_incidence[k] % 8;
                for (std::size_t d = 0; d < 8; ++d)
                    m_rank[64 * std::size_t{e} + 8 * std::size_t{c} + d] = static_cast<std::uint16_t>(place[model.elements()[e].dof_node[d]]);
            }
        }
    }
    if (9 * neighbours.size() > static_cast<std::size_t>(std::numeric_limits<int>::max()))
        throw InputError("solver: the model has too many node couplings (" + std::to_string(9 * neighbours.size()) +
                         " matrix entries) for an assembled matrix; use a coarser level or \"preconditioner\": \"jacobi\"");
    m_matrix.resize(static_cast<Eigen::Index>(3 * n), static_cast<Eigen::Index>(3 * n));
    m_matrix.resizeNonZeros(static_cast<Eigen::Index>(9 * neighbours.size()));
    int* outer = m_matrix.outerIndexPtr();
    int* inner = m_matrix.innerIndexPtr();
    outer[0] = 0;
    for (std::size_t a = 0; a < n; ++a) {
        const std::uint32_t degree = neighbour_start[a + 1] - neighbour_start[a];
        for (std::size_t i = 0; i < 3; ++i) {
            int position = outer[3 * a + i];
            for (std::uint32_t k = neighbour_start[a]; k < neighbour_start[a + 1]; ++k)
                for (int j = 0; j < 3; ++j) inner[position++] = 3 * static_cast<int>(neighbours[k]) + j;
            outer[3 * a + i + 1] = outer[3 * a + i] + static_cast<int>(3 * degree);
        }
    }
    std::fill(m_matrix.valuePtr(), m_matrix.valuePtr() + m_matrix.nonZeros(), 0.0);
}

void ImplicitSolver::set_contact(std::vector<NodeContact> contact)
{
    std::vector<unsigned char> listed(m_x.size(), 0); // checked before anything changes
    for (const NodeContact& c : contact)
        if (c.node >= m_x.size() || listed[c.node]++)
            throw std::invalid_argument("ImplicitSolver::set_contact: node out of range or listed twice");
    for (const NodeContact& c : m_contact) m_contact_of_node[c.node] = -1;
    m_contact = std::move(contact);
    m_contact_x0.resize(m_contact.size());
    for (std::size_t c = 0; c < m_contact.size(); ++c) {
        m_contact_of_node[m_contact[c].node] = static_cast<std::int32_t>(c);
        m_contact_x0[c] = m_x[m_contact[c].node];
    }
}

void ImplicitSolver::adopt_preconditioner(ImplicitSolver& previous, const std::vector<std::uint32_t>& changed_nodes)
{
    if (!previous.m_preconditioner) return;
    set_preconditioner(std::move(previous.m_preconditioner));
    m_last_dt = previous.m_last_dt; // a new dt would invalidate it
    m_preconditioner->blocks_changed(changed_nodes);
}

ImplicitSolver::~ImplicitSolver() = default;
ImplicitSolver::ImplicitSolver(ImplicitSolver&&) noexcept = default;

void ImplicitSolver::set_integrator(std::unique_ptr<NodeIntegrator> integrator) { m_integrator = std::move(integrator); }

void ImplicitSolver::add_contact_forces(const std::vector<Eigen::Vector3d>& at, Eigen::VectorXd& f) const
{
    for (std::size_t c = 0; c < m_contact.size(); ++c) {
        const NodeContact& k = m_contact[c];
        f.segment<3>(static_cast<Eigen::Index>(3 * k.node)) += k.force_n - k.stiffness_n_per_m * (at[k.node] - m_contact_x0[c]);
    }
    m_pairs.add_forces(at, f);
}

double ImplicitSolver::contact_potential(const std::vector<Eigen::Vector3d>& at) const
{
    double u = m_pairs.potential(at);
    for (std::size_t c = 0; c < m_contact.size(); ++c) {
        const NodeContact& k = m_contact[c];
        const Eigen::Vector3d d = at[k.node] - m_contact_x0[c];
        u += -k.force_n.dot(d) + 0.5 * d.dot(k.stiffness_n_per_m * d);
    }
    return u;
}

std::vector<Eigen::Matrix3d> ImplicitSolver::contact_node_stiffness() const
{
    std::vector<Eigen::Matrix3d> k(m_x.size(), Eigen::Matrix3d::Zero());
    for (const NodeContact& c : m_contact) k[c.node] += c.stiffness_n_per_m;
    for (const PairContact& p : m_pairs.pairs()) // the node's own block of k c c^T
        for (const BlockWeight& t : p.terms) k[t.block] += p.stiffness_n_per_m * t.weight * t.weight * p.normal * p.normal.transpose();
    return k;
}

void ImplicitSolver::set_preconditioner(std::unique_ptr<Preconditioner> p)
{
    if (p && m_options.matrix_free)
        throw InputError(std::string("solver: the ") + p->name() + " preconditioner needs an assembled matrix; it cannot run matrix-free");
    m_preconditioner = std::move(p);
}

void ImplicitSolver::fix(std::uint32_t node, unsigned axes)
{
    for (int a = 0; a < 3; ++a)
        if (axes & (1u << a)) m_fixed[3 * node + static_cast<std::size_t>(a)] = m_held[3 * node + static_cast<std::size_t>(a)] = 1;
    if (m_preconditioner) m_preconditioner->invalidate(); // built with other rows held
    m_active_current = false;
}

void ImplicitSolver::set_asleep(const std::vector<unsigned char>& asleep)
{
    m_fixed = m_held;
    for (std::size_t n = 0; n < asleep.size() && n < m_x.size(); ++n)
        if (asleep[n]) {
            m_fixed[3 * n] = m_fixed[3 * n + 1] = m_fixed[3 * n + 2] = 1;
            m_v[n].setZero();
        }
    m_active_current = false; // asleep elements are skipped
    if (m_preconditioner) m_preconditioner->invalidate(); // built with other rows held
}

void ImplicitSolver::update_active()
{
    // An element whose every degree of freedom is held (rigid material, a held piece) moves no
    // node the solve moves, so its rotation, forces and matrix blocks are never needed: skipping
    // it makes a rigid skull cost nothing.
    const auto& elements = m_model.elements();
    m_active.assign(elements.size(), 0);
    for (std::size_t e = 0; e < elements.size(); ++e) {
        for (std::uint32_t n : elements[e].dof_node)
            if (!m_fixed[3 * n] || !m_fixed[3 * n + 1] || !m_fixed[3 * n + 2]) {
                m_active[e] = 1;
                break;
            }
        if (m_active[e]) continue;
        m_element_energy[e] = 0.0;
        m_squeezed[e] = 0;
    }
    m_active_current = true;
    m_element_pass_current = false; // the internal forces it left hold the elements now left out
}

void ImplicitSolver::set_materials(std::vector<MaterialBehaviour> behaviour)
{
    m_element_pass_current = false; // cached forces may hold plastic corrections
    m_behaviour = std::move(behaviour);
    m_behaviour.resize(std::max(m_behaviour.size(), m_model.materials().size()));
    const bool plastic = std::any_of(m_behaviour.begin(), m_behaviour.end(), [](const MaterialBehaviour& b) { return b.plastic(); });
    if (plastic && m_plastic.empty()) m_plastic.assign(m_model.elements().size(), Eigen::Matrix3d::Zero());
    if (!plastic) m_plastic.clear();
    for (std::uint32_t e = 0; e < m_water.size(); ++e) set_water(e, m_water[e]);
}

void ImplicitSolver::set_water(std::uint32_t element, double water)
{
    m_element_pass_current = false;
    if (m_water.empty()) m_water.assign(m_model.elements().size(), 0.0);
    m_water[element] = std::clamp(std::isfinite(water) ? water : 0.0, 0.0, 1.0);
    const auto material = static_cast<std::size_t>(m_model.elements()[element].material);
    const double ratio = material < m_behaviour.size() ? m_behaviour[material].wet_stiffness_ratio : 1.0;
    m_stiffness_scale[element] = 1.0 - (1.0 - ratio) * m_water[element];
}

double ImplicitSolver::plastic_correction(std::size_t e, const Vector24d& u, Vector24d& force)
{
    // One-point plasticity at the material centroid (where the rotation is taken): total strain
    // eps = sym(sum_c u_c grad N_c^T), plastic strain creeping towards the elastic excess; the
    // plastic stress sigma_p = D eps_p acts on the nodes as -V sigma_p grad N_c.
    const HexElement& el = m_model.elements()[e];
    const MaterialBehaviour& b = m_behaviour[static_cast<std::size_t>(el.material)];
    const grid::Lame& lame = m_model.materials()[static_cast<std::size_t>(el.material)].lame;
    Eigen::Matrix3d& plastic = m_plastic[e];
    const double scale = m_stiffness_scale[e];
    Eigen::Matrix3d grad_u = Eigen::Matrix3d::Zero();
    for (int c = 0; c < 8; ++c) grad_u.noalias() += u.segment<3>(3 * c) * el.gradient.row(c);
    const Eigen::Matrix3d strain = 0.5 * (grad_u + grad_u.transpose());
    if (m_update_plastic) {
        const double water = m_water.empty() ? 0.0 : m_water[e];
        const double yield = b.yield_strain * (1.0 - (1.0 - b.wet_yield_ratio) * water);
        const Eigen::Matrix3d elastic = strain - plastic;
        if (elastic.norm() > yield) plastic += std::min(1.0, m_step_dt * b.creep_per_s) * elastic;
        if (const double norm = plastic.norm(); norm > b.max_strain) plastic *= b.max_strain / norm;
    }
    auto stress = [&](const Eigen::Matrix3d& eps) {
        return (2.0 * lame.mu * eps + lame.lambda * eps.trace() * Eigen::Matrix3d::Identity()).eval();
    };
    const Eigen::Matrix3d sigma_p = scale * stress(plastic);
    for (int c = 0; c < 8; ++c) force.segment<3>(3 * c) -= el.volume_m3 * sigma_p * el.gradient.row(c).transpose();
    // Energy of the elastic strain eps - eps_p, relative to the linear part already counted.
    return el.volume_m3 * (-(strain.cwiseProduct(sigma_p)).sum() + 0.5 * plastic.cwiseProduct(sigma_p).sum());
}

double ImplicitSolver::add_volume_correction(std::size_t e, const Eigen::Matrix3d& f, const Eigen::Matrix3d& rotation, double* forces)
{
    // fem/volume_correction.hpp at the material centroid, in the index-aligned frame of f; the
    // world gradient of a function of F_world = frame f is frame times its gradient in f.
    const HexElement& el = m_model.elements()[e];
    const grid::Lame& lame = m_model.materials()[static_cast<std::size_t>(el.material)].lame;
    const double lambda_v = m_stiffness_scale[e] * lame.lambda * el.volume_m3;
    double plastic_volume = 1.0, plastic_trace = 0.0; // the plastic strain's own volume change is its rest
    if (!m_plastic.empty() && m_behaviour[static_cast<std::size_t>(el.material)].plastic()) {
        plastic_volume = (Eigen::Matrix3d::Identity() + m_plastic[e]).determinant();
        plastic_trace = m_plastic[e].trace();
    }
    const VolumeCorrection c = volume_correction(f, rotation, lambda_v, plastic_volume, plastic_trace);
    m_squeezed[e] = 0;
    if (c.gradient.isZero(0.0)) return c.energy; // not squeezed (most elements): nothing to add
    const Eigen::Matrix3d& frame = m_model.frame();
    scatter_add(gradient_times(frame * c.gradient, el.gradient), forces, el.dof_node);
    if (!c.hessian.active()) return c.energy;
    m_volume_hessian[e] = c.hessian.turned(frame);
    m_squeezed[e] = 1;
    return c.energy;
}

double ImplicitSolver::assemble(double m_scale, double k_scale, Output output)
{
    const Eigen::Matrix3d& frame = m_model.frame();
    const auto& elements = m_model.elements();
    if (!m_active_current) update_active();
    // Element pass: rotation, corotated displacements, elastic forces and energy. A dynamic step
    // ends with this pass at its new positions (the energy check); the next step starts from the
    // same positions and reuses it, unless plastic strain is due to creep first.
    if (!(m_element_pass_current && m_plastic.empty())) {
        // Each element adds its forces straight into its nodes (for_each_element_by_runs).
        m_internal.setZero(static_cast<Eigen::Index>(3 * m_x.size()));
        for_each_element_by_runs([&](const std::array<std::size_t, 4>& batch, int count) {
            // Displacements relative to corner 0: K ignores translations, and far from the origin
            // (a scan sits ~0.2 m away) subtracting them first keeps the small strains exact.
            std::array<CornerVectors, 4> moved; // each corner's position less corner 0's
            std::array<Eigen::Matrix3d, 4> f;   // deformation gradients, index-aligned frame
            std::array<const Eigen::Matrix3d*, 4> from{};
            std::array<Eigen::Quaterniond*, 4> to{};
            for (std::size_t i = 0; i < static_cast<std::size_t>(count); ++i) {
                const HexElement& el = elements[batch[i]];
                moved[i] = minus(gather(m_x.front().data(), el.dof_node), m_x[el.dof_node[0]]);
                f[i] = frame.transpose() * outer_sum(moved[i], el.gradient);
                from[i] = &f[i];
                to[i] = &m_rotation[batch[i]];
            }
            extract_rotations(from.data(), to.data(), count);
            for (std::size_t i = 0; i < static_cast<std::size_t>(count); ++i) {
                const std::size_t e = batch[i];
                const HexElement& el = elements[e];
                const Eigen::Matrix3d local_rotation = m_rotation[e].toRotationMatrix();
                const Eigen::Matrix3d r = frame * local_rotation;
                m_element_rotation[e] = r;
                const CornerVectors rest = from_corner_major(el.rest);
                const CornerVectors u = turn(r, moved[i], true) - minus(rest, Eigen::Vector3d(rest.at(0, 0), rest.at(0, 1), rest.at(0, 2)));
                CornerVectors fl = m_stiffness_scale[e] * stiffness_times(*el.stiffness, u);
                m_element_energy[e] = 0.5 * dot(u, fl);
                if (!m_plastic.empty() && m_behaviour[static_cast<std::size_t>(el.material)].plastic()) {
                    Vector24d force = to_corner_major(fl);
                    m_element_energy[e] += plastic_correction(e, to_corner_major(u), force);
                    fl = from_corner_major(force);
                }
                scatter_add(turn(r, fl, false), m_internal.data(), el.dof_node);
                m_element_energy[e] += add_volume_correction(e, f[i], local_rotation, m_internal.data());
            }
        });
    }
    m_element_pass_current = true;
    double* values = m_matrix.valuePtr();
    const bool lumped = m_options.lumped_mass;
    m_m_scale = m_scale;
    m_k_scale = k_scale;
    m_matrix_current = output == Output::matrix;
    if (output == Output::diagonal) { // for the Jacobi preconditioner and the scaled residual
        // Each element adds the diagonals of its corners' blocks into its nodes, then each node
        // its mass and contact.
        m_diagonal.setZero(static_cast<Eigen::Index>(3 * m_x.size()));
        for_each_element_by_runs(each_element([&](std::size_t e) {
            const HexElement& el = elements[e];
            const Eigen::Matrix3d& r = m_element_rotation[e];
            const double ks = k_scale * m_stiffness_scale[e];
            for (int c = 0; c < 8; ++c) {
                // The diagonal of r K_cc r^T alone: row i of r K_cc dotted with row i of r.
                const Eigen::Matrix3d rk = r * corner_block(*el.stiffness, c, c);
                Eigen::Vector3d d = ks * rk.cwiseProduct(r).rowwise().sum();
                if (!lumped) d.array() += m_scale * el.mass(c, c);
                if (m_squeezed[e]) {
                    const Eigen::Vector3d g = el.gradient.row(c).transpose();
                    d += k_scale * m_volume_hessian[e].block(g, g).diagonal();
                }
                m_diagonal.segment<3>(3 * static_cast<Eigen::Index>(el.dof_node[c])) += d;
            }
        }));
        for (std::size_t n = 0; n < m_x.size(); ++n) {
            Eigen::Vector3d d = Eigen::Vector3d::Constant(m_scale * (lumped ? m_model.nodal_mass()[n] : m_model.added_mass()[n]));
            if (const std::int32_t c = m_contact_of_node[n]; c >= 0)
                d += m_contact_scale * m_contact[static_cast<std::size_t>(c)].stiffness_n_per_m.diagonal();
            m_diagonal.segment<3>(static_cast<Eigen::Index>(3 * n)) += d;
        }
    }
    if (output == Output::matrix) {
        // Each node writes its own three rows, so threads never write the same entry and every
        // write stays within a few cache lines.
        m_diagonal.resize(static_cast<Eigen::Index>(3 * m_x.size()));
        tbb::parallel_for(tbb::blocked_range<std::size_t>(0, m_x.size(), 256), [&](const tbb::blocked_range<std::size_t>& range) {
            for (std::size_t n = range.begin(); n != range.end(); ++n) {
                const double diagonal_mass = lumped ? m_model.nodal_mass()[n] : m_model.added_mass()[n];
                const int* outer = m_matrix.outerIndexPtr();
                std::fill(values + outer[3 * n], values + outer[3 * n + 3], 0.0); // this node's three rows
                const int row_length = outer[3 * n + 1] - outer[3 * n];
                for (std::uint32_t k = m_incidence_start[n]; k < m_incidence_start[n + 1]; ++k) {
                    const std::uint32_t e = m_incidence[k] / 8, c = m_incidence[k] % 8;
                    if (!m_active[e]) continue;
                    const HexElement& el = elements[e];
                    const Eigen::Matrix3d& r = m_element_rotation[e];
                    const Eigen::Matrix3d rk = (k_scale * m_stiffness_scale[e]) * r;
                    const std::uint16_t* ranks = &m_rank[64 * std::size_t{e} + 8 * c];
                    const bool squeezed = m_squeezed[e] != 0;
                    const VolumeHessian& v = m_volume_hessian[e]; // read only where squeezed
                    for (int d = 0; d < 8; ++d) {
                        Eigen::Matrix3d block = rk * corner_block(*el.stiffness, static_cast<int>(c), d) * r.transpose();
                        if (!lumped) block.diagonal().array() += m_scale * el.mass(c, d);
                        if (squeezed) block += k_scale * v.block(el.gradient.row(c).transpose(), el.gradient.row(d).transpose());
                        double* at = values + outer[3 * n] + 3 * ranks[d];
                        for (int i = 0; i < 3; ++i)
                            for (int j = 0; j < 3; ++j) at[i * row_length + j] += block(i, j);
                    }
                }
                double* diagonal = values + outer[3 * n] + 3 * m_diagonal_rank[n];
                if (const std::int32_t c = m_contact_of_node[n]; c >= 0)
                    for (int i = 0; i < 3; ++i)
                        for (int j = 0; j < 3; ++j)
                            diagonal[i * row_length + j] += m_contact_scale * m_contact[static_cast<std::size_t>(c)].stiffness_n_per_m(i, j);
                for (int i = 0; i < 3; ++i) {
                    diagonal[i * row_length + i] += m_scale * diagonal_mass;
                    m_diagonal[static_cast<Eigen::Index>(3 * n) + i] = diagonal[i * row_length + i];
                }
            }
        });
    }
    if (output != Output::forces) m_pairs.add_diagonal(m_contact_scale, m_diagonal);
    m_pair_in_matrix.assign(m_pairs.pairs().size(), 0);
    if (output == Output::matrix) pairs_into_matrix(1.0);
    m_update_plastic = false;
    double energy = 0.0;
    for (double e : m_element_energy) energy += e;
    return energy;
}

void ImplicitSolver::pairs_into_matrix(double sign, const std::vector<std::size_t>* which)
{
    auto add = [&](std::size_t i) {
        if (sign > 0.0) m_pair_in_matrix[i] = add_to_matrix(m_pairs.pairs()[i], m_contact_scale, m_fixed, m_matrix);
        else if (m_pair_in_matrix[i]) add_to_matrix(m_pairs.pairs()[i], -m_contact_scale, m_fixed, m_matrix);
    };
    if (which) for (std::size_t i : *which) add(i);
    else for (std::size_t i = 0; i < m_pairs.pairs().size(); ++i) add(i);
}

std::vector<Eigen::Vector3d> ImplicitSolver::free_step_positions(double dt) const
{
    std::vector<Eigen::Vector3d> out(m_x.size());
    for (std::size_t n = 0; n < m_x.size(); ++n) {
        out[n] = m_x[n];
        for (int a = 0; a < 3; ++a)
            if (!m_fixed[3 * n + static_cast<std::size_t>(a)]) out[n][a] += dt * (m_v[n][a] + dt * m_gravity[a]);
    }
    return out;
}

void ImplicitSolver::mass_times(const std::vector<Eigen::Vector3d>& v, Eigen::VectorXd& out) const
{
    out.resize(static_cast<Eigen::Index>(3 * v.size()));
    const auto& elements = m_model.elements();
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, v.size(), 256), [&](const tbb::blocked_range<std::size_t>& range) {
        for (std::size_t n = range.begin(); n != range.end(); ++n) {
            Eigen::Vector3d sum = Eigen::Vector3d::Zero();
            if (m_options.lumped_mass) {
                sum = m_model.nodal_mass()[n] * v[n];
            } else {
                for (std::uint32_t k = m_incidence_start[n]; k < m_incidence_start[n + 1]; ++k) {
                    const HexElement& el = elements[m_incidence[k] / 8];
                    const std::uint32_t c = m_incidence[k] % 8;
                    for (int d = 0; d < 8; ++d) sum += el.mass(c, d) * v[el.dof_node[d]];
                }
                sum += m_model.added_mass()[n] * v[n];
            }
            out.segment<3>(static_cast<Eigen::Index>(3 * n)) = sum;
        }
    });
}

double ImplicitSolver::elastic_energy() { return assemble(0.0, 0.0, Output::forces); }

ImplicitSolver::Output ImplicitSolver::system_output() const
{
    if (m_options.matrix_free) return Output::diagonal;
    return m_preconditioner && !m_preconditioner->needs_matrix() ? Output::diagonal : Output::matrix;
}

Eigen::VectorXd ImplicitSolver::external_force() const
{
    Eigen::VectorXd f(static_cast<Eigen::Index>(3 * m_x.size()));
    for (std::size_t n = 0; n < m_x.size(); ++n)
        // Gravity on the whole lumped mass, the floor added to nearly empty corners included
        // (HexModel::added_mass): a uniform field then accelerates a free piece rigidly. On the
        // real material alone it pulled those corners less than their inertia, so a free-falling
        // piece bent by itself, a stiff one stored the bending as elastic energy, and the energy
        // guard split its steps (the skull phantom's loose fragments at E = 1e9 Pa: a substep in
        // every frame from the tenth, 81 ms a step; now none, 12 ms). The weight added is the
        // floor's: at most 1e-3 of a full cell corner's mass at each nearly empty node.
        f.segment<3>(static_cast<Eigen::Index>(3 * n)) = m_model.nodal_mass()[n] * m_gravity + m_external[n];
    add_contact_forces(m_x, f);
    return f;
}

void ImplicitSolver::apply_constraints(Eigen::VectorXd& rhs)
{
    condense(rhs); // a tied node's load acts on the coarse nodes it follows
    // Held degrees of freedom: identity rows and columns, zero right-hand side.
    if (m_matrix_current)
        for (Eigen::Index row = 0; row < m_matrix.outerSize(); ++row)
            for (SystemMatrix::InnerIterator it(m_matrix, row); it; ++it)
                if (m_fixed[static_cast<std::size_t>(row)] || m_fixed[static_cast<std::size_t>(it.col())])
                    it.valueRef() = (row == it.col()) ? 1.0 : 0.0;
    for (Eigen::Index i = 0; i < rhs.size(); ++i)
        if (m_fixed[static_cast<std::size_t>(i)]) {
            rhs[i] = 0.0;
            m_diagonal[i] = 1.0;
        }
}

void ImplicitSolver::multiply(const Eigen::VectorXd& p, Eigen::VectorXd& out) const
{
    if (m_model.ties().empty()) return multiply_full(p, out);
    // On the free space of a model of two levels, T^T A T p: the tied nodes take the values of the
    // coarse nodes they follow, and hand their products back to them. CG keeps tied entries zero,
    // and they map to themselves as held ones do.
    m_tied_p = p;
    expand(m_tied_p);
    multiply_full(m_tied_p, out);
    condense(out);
    for (const grid::MixedLevels::Tie& t : m_model.ties()) out.segment<3>(3 * static_cast<Eigen::Index>(t.node)) = p.segment<3>(3 * static_cast<Eigen::Index>(t.node));
    for (Eigen::Index i = 0; i < out.size(); ++i)
        if (m_fixed[static_cast<std::size_t>(i)]) out[i] = p[i];
}

void ImplicitSolver::expand(Eigen::VectorXd& v) const
{
    for (const grid::MixedLevels::Tie& t : m_model.ties()) {
        Eigen::Vector3d sum = Eigen::Vector3d::Zero();
        for (std::size_t c = 0; c < 8; ++c)
            if (t.weights[c] != 0.0) sum += t.weights[c] * v.segment<3>(3 * static_cast<Eigen::Index>(t.masters[c]));
        v.segment<3>(3 * static_cast<Eigen::Index>(t.node)) = sum;
    }
}

void ImplicitSolver::condense(Eigen::VectorXd& v) const
{
    for (const grid::MixedLevels::Tie& t : m_model.ties()) {
        const Eigen::Vector3d own = v.segment<3>(3 * static_cast<Eigen::Index>(t.node));
        for (std::size_t c = 0; c < 8; ++c)
            if (t.weights[c] != 0.0) v.segment<3>(3 * static_cast<Eigen::Index>(t.masters[c])) += t.weights[c] * own;
        v.segment<3>(3 * static_cast<Eigen::Index>(t.node)).setZero();
    }
}

void ImplicitSolver::multiply_full(const Eigen::VectorXd& p, Eigen::VectorXd& out) const
{
    if (!m_matrix_current) multiply_element_wise(p, out);
    else multiply_matrix(p, out);
    // Pair contacts couple nodes the matrix's pattern may not join (two pieces): added here.
    m_pairs.add_product(p, m_contact_scale, m_fixed, out, m_matrix_current ? &m_pair_in_matrix : nullptr);
}

void ImplicitSolver::multiply_matrix(const Eigen::VectorXd& p, Eigen::VectorXd& out) const
{
    const int* outer = m_matrix.outerIndexPtr();
    const int* inner = m_matrix.innerIndexPtr();
    const double* values = m_matrix.valuePtr();
    out.resize(p.size());
    tbb::parallel_for(tbb::blocked_range<Eigen::Index>(0, p.size(), 2048), [&](const tbb::blocked_range<Eigen::Index>& r) {
        for (Eigen::Index row = r.begin(); row != r.end(); ++row) {
            double sum = 0.0;
            for (int k = outer[row]; k < outer[row + 1]; ++k) sum += values[k] * p[inner[k]];
            out[row] = sum;
        }
    });
}

void ImplicitSolver::multiply_element_wise(const Eigen::VectorXd& p, Eigen::VectorXd& out) const
{
    // out = m_scale M p + k_scale sum_e R K R^T p, element by element; held dofs map to themselves
    // (CG keeps them zero in p). Each element adds its product straight into its nodes: the runs
    // of one group share no node, so they run in parallel without two writing the same entry.
    const auto& elements = m_model.elements();
    m_stiffness_product.setZero(p.size());
    for_each_element_by_runs(each_element([&](std::size_t e) {
        const HexElement& el = elements[e];
        const Eigen::Matrix3d& r = m_element_rotation[e];
        const CornerVectors local = turn(r, gather(p.data(), el.dof_node), true);
        scatter_add(turn(r, m_stiffness_scale[e] * stiffness_times(*el.stiffness, local), false), m_stiffness_product.data(), el.dof_node);
        if (m_squeezed[e]) // a byte a element: the 176-byte Hessian is read only where it is not zero
            scatter_add(gradient_times(m_volume_hessian[e].times(outer_sum(gather(p.data(), el.dof_node), el.gradient)), el.gradient), m_stiffness_product.data(),
                        el.dof_node);
    }));
    out.resize(p.size());
    const bool lumped = m_options.lumped_mass;
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, m_x.size(), 256), [&](const tbb::blocked_range<std::size_t>& range) {
        for (std::size_t n = range.begin(); n != range.end(); ++n) {
            const auto i = static_cast<Eigen::Index>(3 * n);
            Eigen::Vector3d mass = Eigen::Vector3d::Zero();
            if (!lumped)
                for (std::uint32_t k = m_incidence_start[n]; k < m_incidence_start[n + 1]; ++k) {
                    const std::uint32_t e = m_incidence[k] / 8, c = m_incidence[k] % 8;
                    for (int d = 0; d < 8; ++d) mass += elements[e].mass(c, d) * p.segment<3>(3 * static_cast<Eigen::Index>(elements[e].dof_node[d]));
                }
            mass += (lumped ? m_model.nodal_mass()[n] : m_model.added_mass()[n]) * p.segment<3>(i);
            out.segment<3>(i) = m_k_scale * m_stiffness_product.segment<3>(i) + m_m_scale * mass;
            if (const std::int32_t c = m_contact_of_node[n]; c >= 0)
                out.segment<3>(i) += m_contact_scale * (m_contact[static_cast<std::size_t>(c)].stiffness_n_per_m * p.segment<3>(i));
            for (int a = 0; a < 3; ++a)
                if (m_fixed[3 * n + static_cast<std::size_t>(a)]) out[i + a] = p[i + a];
        }
    });
}

void ImplicitSolver::update_node_rotations()
{
    // The mean of the elements' quaternions, each taken with the sign nearer the running sum.
    std::vector<Eigen::Vector4d> sum(m_x.size(), Eigen::Vector4d::Zero());
    const auto& elements = m_model.elements();
    for (std::size_t e = 0; e < elements.size(); ++e)
        if (m_active[e])
            for (std::uint32_t n : elements[e].dof_node) accumulate_rotation(sum[n], m_rotation[e]);
    for (std::size_t n = 0; n < m_x.size(); ++n)
        if (sum[n].squaredNorm() > 0.0) m_node_rotation[n].coeffs() = sum[n].normalized();
}

int ImplicitSolver::solve(const Eigen::VectorXd& rhs, Eigen::VectorXd& x, double& residual, bool same_system, double tolerance)
{
    const Eigen::Index n = rhs.size();
    // Two levels: a tied node's diagonal counts on the nodes it follows (weights squared), its own
    // is 1, and CG starts it at zero (it keeps it there).
    Eigen::VectorXd tied_diagonal;
    if (!m_model.ties().empty()) {
        tied_diagonal = m_diagonal;
        for (const grid::MixedLevels::Tie& t : m_model.ties()) {
            const auto i = 3 * static_cast<Eigen::Index>(t.node);
            for (std::size_t c = 0; c < 8; ++c)
                tied_diagonal.segment<3>(3 * static_cast<Eigen::Index>(t.masters[c])) += t.weights[c] * t.weights[c] * m_diagonal.segment<3>(i);
            tied_diagonal.segment<3>(i).setOnes();
            x.segment<3>(i).setZero();
        }
    }
    const Eigen::VectorXd& diagonal = m_model.ties().empty() ? m_diagonal : tied_diagonal;
    Eigen::VectorXd inv_d(n), inv_sqrt_d(n);
    for (Eigen::Index i = 0; i < n; ++i) {
        const double d = diagonal[i];
        inv_d[i] = d > 0.0 ? 1.0 / d : 1.0;
        inv_sqrt_d[i] = std::sqrt(inv_d[i]);
    }
    if (m_preconditioner && !same_system) {
        update_node_rotations();
        std::vector<std::uint32_t> contacts;
        for (const NodeContact& c : m_contact) contacts.push_back(c.node);
        for (const PairContact& p : m_pairs.pairs())
            for (const BlockWeight& t : p.terms) contacts.push_back(t.block);
        m_preconditioner->set_contact_blocks(std::move(contacts));
        m_preconditioner->update(m_matrix_current ? &m_matrix : nullptr, m_fixed, m_node_rotation);
        if (m_preconditioner->failed()) {
            const FactorFailure failure = m_preconditioner->failure();
            const auto node = static_cast<std::size_t>(failure.dof / 3);
            const bool known = failure.dof >= 0 && node < m_x.size();
            const bool held = std::any_of(m_fixed.begin(), m_fixed.end(), [](unsigned char f) { return f != 0; });
            m_fallback_note = fem::fallback_note(m_preconditioner->name(), failure, known ? &m_x[node] : nullptr, m_options.quasi_static, held);
            m_preconditioner.reset();
        }
    }
    auto precondition = [&](const Eigen::VectorXd& res, Eigen::VectorXd& out) {
        if (m_preconditioner)
            m_preconditioner->apply(res, out);
        else
            out = res.cwiseProduct(inv_d);
        // On the free space: a principal part of an SPD preconditioner is SPD.
        for (const grid::MixedLevels::Tie& t : m_model.ties()) out.segment<3>(3 * static_cast<Eigen::Index>(t.node)).setZero();
    };
    const CgResult cg = conjugate_gradient([this](const Eigen::VectorXd& p, Eigen::VectorXd& out) { multiply(p, out); }, precondition, rhs,
                                           inv_sqrt_d, tolerance > 0.0 ? tolerance : m_options.cg_tolerance,
                                           m_options.cg_max_iterations, x);
    residual = cg.residual;
    expand(x);
    if (m_preconditioner && !same_system) m_preconditioner->report_iterations(cg.iterations);
    return cg.iterations;
}

namespace {
double ms_since(std::chrono::steady_clock::time_point t)
{
    return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t).count();
}
} // namespace

double ImplicitSolver::kinetic_energy() const
{
    Eigen::VectorXd mv;
    mass_times(m_v, mv);
    return 0.5 * Eigen::Map<const Eigen::VectorXd>(m_v.front().data(), mv.size()).dot(mv);
}

double ImplicitSolver::linear_step(double dt, StepStats& s, double& energy_before)
{
    const auto n = static_cast<Eigen::Index>(3 * m_x.size());
    Eigen::Map<Eigen::VectorXd> v(m_v.front().data(), n);
    Eigen::Map<Eigen::VectorXd> x(m_x.front().data(), n);
    Eigen::VectorXd f_ext = external_force();
    if (dt != m_last_dt && m_preconditioner) m_preconditioner->invalidate(); // its matrix depends on dt
    m_last_dt = dt;
    m_step_dt = dt;
    m_contact_scale = dt * dt;
    auto t = std::chrono::steady_clock::now();
    energy_before = kinetic_energy() +
                    assemble(1.0 + dt * m_options.rayleigh_mass_per_s, dt * m_options.rayleigh_stiffness_s + dt * dt, system_output());
    Eigen::VectorXd rhs;
    mass_times(m_v, rhs);
    rhs += dt * (f_ext - m_internal);
    apply_constraints(rhs);
    s.assembly_ms += ms_since(t);
    t = std::chrono::steady_clock::now();
    Eigen::VectorXd next = v;
    for (Eigen::Index i = 0; i < n; ++i)
        if (m_fixed[static_cast<std::size_t>(i)]) next[i] = 0.0;
    double residual = 0.0;
    s.cg_iterations += solve(rhs, next, residual);
    // A pair contact is linear in the solve and would pull two sides that part during the step
    // back together (a piece rocking on another sticks to it by one edge): those let go, the
    // waiting ones that end pressed in join, and the step is solved again (from the last answer),
    // until nothing changes (k_release_passes).
    for (int pass = 0; pass < k_release_passes && !m_pairs.empty(); ++pass) {
        const std::vector<Eigen::Vector3d> end = m_pairs.step_end(m_x, dt, next);
        const std::vector<std::size_t> pulling = m_pairs.pulling(end), arriving = m_pairs.arriving(end);
        if (pulling.empty() && arriving.empty()) break;
        if (m_matrix_current) pairs_into_matrix(-1.0, &pulling);
        m_pairs.release(pulling);
        m_pairs.activate(arriving);
        if (m_matrix_current) pairs_into_matrix(1.0, &arriving);
        f_ext = external_force();
        mass_times(m_v, rhs);
        rhs += dt * (f_ext - m_internal);
        apply_constraints(rhs);
        s.cg_iterations += solve(rhs, next, residual, true);
    }
    s.residual = std::max(s.residual, residual);
    s.converged = s.converged && residual <= m_options.cg_tolerance;
    s.solve_ms += ms_since(t);
    v = next;
    x += dt * v;
    m_element_pass_current = false;
    // Work of the external forces over the step; a contact force falls linearly along the step
    // (f - dt K v at its end), so its mean is f - dt K v / 2.
    double contact_correction = 0.0;
    for (const NodeContact& c : m_contact)
        contact_correction += m_v[c.node].dot(c.stiffness_n_per_m * m_v[c.node]);
    contact_correction += m_pairs.stiffness_product(m_v);
    return dt * f_ext.dot(v) - 0.5 * dt * dt * contact_correction;
}

double ImplicitSolver::incremental_potential(double dt, const std::vector<Eigen::Vector3d>& x0, const Eigen::VectorXd& m_v0)
{
    const auto n = static_cast<Eigen::Index>(3 * m_x.size());
    for (std::size_t i = 0; i < m_x.size(); ++i) m_x[i] = x0[i] + dt * m_v[i];
    m_element_pass_current = false;
    const double psi = assemble(0.0, 0.0, Output::forces);
    Eigen::VectorXd mv;
    mass_times(m_v, mv);
    const Eigen::Map<const Eigen::VectorXd> v(m_v.front().data(), n);
    double u = 0.0; // gravity and loads (constant forces), contact springs
    for (std::size_t i = 0; i < m_x.size(); ++i)
        u -= (m_model.nodal_mass()[i] * m_gravity + m_external[i]).dot(m_x[i]);
    for (std::size_t c = 0; c < m_contact.size(); ++c) {
        const NodeContact& k = m_contact[c];
        const Eigen::Vector3d d = m_x[k.node] - m_contact_x0[c];
        u += -k.force_n.dot(d) + 0.5 * d.dot(k.stiffness_n_per_m * d);
    }
    u += m_pairs.potential(m_x);
    return 0.5 * (1.0 + dt * m_options.rayleigh_mass_per_s) * v.dot(mv) - v.dot(m_v0) + psi + u;
}

double ImplicitSolver::newton_step(double dt, StepStats& s, double& energy_before)
{
    const auto n = static_cast<Eigen::Index>(3 * m_x.size());
    const std::vector<Eigen::Vector3d> x0 = m_x;
    if (dt != m_last_dt && m_preconditioner) m_preconditioner->invalidate();
    m_last_dt = dt;
    m_step_dt = dt;
    m_contact_scale = dt * dt;
    const double a = 1.0 + dt * m_options.rayleigh_mass_per_s;
    m_element_pass_current = false;
    energy_before = kinetic_energy() + assemble(0.0, 0.0, Output::forces);
    Eigen::VectorXd m_v0;
    mass_times(m_v, m_v0);
    const Eigen::VectorXd f_start = external_force();
    const double scale = m_v0.norm() + dt * f_start.norm() + 1e-300;
    Eigen::Map<Eigen::VectorXd> v(m_v.front().data(), n);
    for (Eigen::Index i = 0; i < n; ++i)
        if (m_fixed[static_cast<std::size_t>(i)]) v[i] = 0.0;
    double phi = incremental_potential(dt, x0, m_v0);
    bool converged = false;
    double previous_residual = std::numeric_limits<double>::infinity();
    for (int it = 0; it < m_options.newton_max_iterations && !converged; ++it) {
        auto t = std::chrono::steady_clock::now();
        for (std::size_t i = 0; i < m_x.size(); ++i) m_x[i] = x0[i] + dt * m_v[i];
        m_element_pass_current = false;
        assemble(a, dt * dt, system_output()); // rotations, forces and the Hessian at this iterate
        Eigen::VectorXd mv;
        mass_times(m_v, mv);
        Eigen::VectorXd rhs = m_v0 - a * mv + dt * (external_force() - m_internal); // -gradient of Phi
        apply_constraints(rhs);
        s.assembly_ms += ms_since(t);
        s.residual = rhs.norm() / scale;
        if (s.residual <= m_options.cg_tolerance) {
            converged = true;
            break;
        }
        t = std::chrono::steady_clock::now();
        Eigen::VectorXd dv = Eigen::VectorXd::Zero(n);
        double cg_residual = 0.0;
        // Inexact Newton (Dembo, Eisenstat and Steihaug 1982): far from the solution a direction
        // to two digits does as well (solving each to the scene's 1e-6 took three to five times
        // the CG iterations for the same iterates); near it, as exact as the residual is small,
        // which keeps the convergence quadratic, and never beyond what the step's tolerance needs.
        // (Inexact directions to the end stall: there Phi's decrease is below its round-off.)
        const double forcing = std::max(m_options.cg_tolerance / s.residual, std::min(1e-2, s.residual));
        s.cg_iterations += solve(rhs, dv, cg_residual, false, forcing);
        s.solve_ms += ms_since(t);
        ++s.newton_iterations;
        // Backtracking (Armijo) on Phi along the Newton direction.
        const Eigen::VectorXd v_start = v;
        const double slope = -rhs.dot(dv);
        double step = 1.0, next = phi;
        for (int k = 0; k < 30; ++k, step *= 0.5) {
            v = v_start + step * dv;
            next = incremental_potential(dt, x0, m_v0);
            if (std::isfinite(next) && next <= phi + 1e-4 * step * slope) break;
        }
        if (!(std::isfinite(next) && next <= phi + 1e-4 * step * slope)) { // no descent left: as close as it gets
            v = v_start;
            next = incremental_potential(dt, x0, m_v0);
            converged = true;
        }
        // Crawling: a decrease the energy guard's slack (1e-3 of the energy) could never notice,
        // while the residual shrinks by less than a fifth (more than ten iterations a digit).
        // Along a full step, the corotational force is not the exact gradient of Phi and the
        // iterations would only creep on: the step stops there, reported as not converged. Along
        // a step cut to almost nothing, Phi's decrease is below its round-off: as close as it
        // gets, as when no descent is left.
        const bool crawling = phi - next <= 1e-6 * energy_before && s.residual > 0.8 * previous_residual;
        previous_residual = s.residual;
        for (std::size_t i = 0; i < m_x.size(); ++i) m_x[i] = x0[i] + dt * m_v[i];
        if (m_pairs.settle(m_x) > 0) next = incremental_potential(dt, x0, m_v0); // a contact only pushes
        phi = next;
        if (crawling && step < 1e-3) converged = true;
        if (crawling && !converged) break;
    }
    s.converged = s.converged && converged;
    for (std::size_t i = 0; i < m_x.size(); ++i) m_x[i] = x0[i] + dt * m_v[i];
    m_element_pass_current = false;
    double contact_correction = 0.0;
    for (const NodeContact& c : m_contact) contact_correction += m_v[c.node].dot(c.stiffness_n_per_m * m_v[c.node]);
    contact_correction += m_pairs.stiffness_product(m_v);
    return dt * f_start.dot(v) - 0.5 * dt * dt * contact_correction;
}

void ImplicitSolver::advance(double dt, int depth, StepStats& s)
{
    // One linearised step keeps the rotations of its start: for a large step (a stiff kick, a
    // big dt, a released twist) the end state can hold more energy than the start plus the work
    // of the loads, which no physical step does. Such a step is undone and taken as two halves,
    // down to 1/32 of the frame; a step still gaining energy there is kept and reported.
    constexpr int max_depth = 5;
    const std::vector<Eigen::Vector3d> x0 = m_x, v0 = m_v;
    const std::vector<Eigen::Matrix3d> plastic0 = m_plastic;
    // The rotations' warm start too: a failed attempt's trial positions (a line search's long
    // steps) can leave it on another branch, and the next attempt must start as this one did.
    const std::vector<Eigen::Quaterniond> rotation0 = m_rotation;
    m_update_plastic = !m_plastic.empty();
    const bool converged0 = s.converged;
    const double residual0 = s.residual;
    double before = 0.0;
    const double work = linear_step(dt, s, before);
    s.kinetic_energy_j = kinetic_energy();
    s.elastic_energy_j = elastic_energy();
    const double after = s.kinetic_energy_j + s.elastic_energy_j;
    const double slack = 1e-3 * (before + std::abs(work)) + 1e-15;
    bool physical = std::isfinite(after) && after <= before + work + slack; // NaN is never physical
    if (physical) return;
    auto undo = [&] {
        s.converged = converged0; // the undone attempt does not count
        s.residual = residual0;
        m_x = x0;
        m_element_pass_current = false;
        m_v = v0;
        m_plastic = plastic0;
        m_rotation = rotation0;
    };
    // The linearised step kept its start's rotations and created energy: solve the step fully.
    undo();
    m_update_plastic = !m_plastic.empty();
    const double newton_work = newton_step(dt, s, before);
    s.kinetic_energy_j = kinetic_energy();
    s.elastic_energy_j = elastic_energy();
    const double newton_after = s.kinetic_energy_j + s.elastic_energy_j;
    physical = std::isfinite(newton_after) &&
               newton_after <= before + newton_work + 1e-3 * (before + std::abs(newton_work)) + 1e-15;
    if (physical) return;
    if (depth == max_depth || m_projected_this_step) {
        // Still gaining energy at 1/32 of the frame (the Newton solve stopped short: corotational
        // forces are not the exact gradient of the energy, and under a slam its line search stalls).
        // Rather than stop the session, the step keeps its direction and loses the energy it made.
        // Once a frame has had to do this its other substeps are not halved further: halving to
        // 1/32 everywhere cost up to 63 full solves a frame (seconds) for no better answer.
        project_energy(x0, before + newton_work, s);
        return;
    }
    undo();
    ++s.substeps;
    advance(0.5 * dt, depth + 1, s);
    advance(0.5 * dt, depth + 1, s);
}

void ImplicitSolver::project_energy(const std::vector<Eigen::Vector3d>& x0, double allowed, StepStats& s)
{
    // Kinetic energy first: the velocities are scaled so that kinetic plus elastic energy is what
    // the step may hold. When the elastic energy alone is too much, the object stops and its
    // positions go back along the step (bisection) until it is not.
    s.energy_projected = true;
    m_projected_this_step = true;
    const double elastic = s.elastic_energy_j, kinetic = s.kinetic_energy_j;
    if (std::isfinite(elastic) && std::isfinite(kinetic) && elastic <= allowed) {
        const double scale = kinetic > 0.0 ? std::sqrt(std::max(0.0, allowed - elastic) / kinetic) : 0.0;
        if (scale < 1.0)
            for (Eigen::Vector3d& v : m_v) v *= scale;
        s.kinetic_energy_j = kinetic * std::min(1.0, scale * scale);
        return;
    }
    const std::vector<Eigen::Vector3d> x1 = m_x;
    for (Eigen::Vector3d& v : m_v) v.setZero();
    double lo = 0.0, hi = 1.0;
    for (int k = 0; k < 30; ++k) {
        const double t = 0.5 * (lo + hi);
        for (std::size_t i = 0; i < m_x.size(); ++i) m_x[i] = x0[i] + t * (x1[i] - x0[i]);
        m_element_pass_current = false;
        const double e = elastic_energy();
        (std::isfinite(e) && e <= allowed ? lo : hi) = t;
    }
    for (std::size_t i = 0; i < m_x.size(); ++i) m_x[i] = x0[i] + lo * (x1[i] - x0[i]);
    m_element_pass_current = false;
    s.kinetic_energy_j = 0.0;
    s.elastic_energy_j = elastic_energy();
}

StepStats ImplicitSolver::step()
{
    const auto start = std::chrono::steady_clock::now();
    StepStats s;
    if (m_integrator) {
        s = m_integrator->step(*this);
        m_element_pass_current = false;
        m_pairs.settle(m_x); // a contact only pushes
    } else if (!m_options.quasi_static) {
        m_projected_this_step = false;
        advance(m_options.dt_s, 0, s);
    } else {
        m_update_plastic = !m_plastic.empty(); // plastic strain creeps once per frame, at its start
        m_step_dt = m_options.dt_s;
        m_contact_scale = 1.0;
        const auto n = static_cast<Eigen::Index>(3 * m_x.size());
        Eigen::VectorXd f_ext = external_force();
        Eigen::Map<Eigen::VectorXd> v(m_v.front().data(), n);
        Eigen::Map<Eigen::VectorXd> x(m_x.front().data(), n);
        v.setZero();
        double scale = 0.0;
        for (Eigen::Index i = 0; i < n; ++i)
            if (!m_fixed[static_cast<std::size_t>(i)]) scale += f_ext[i] * f_ext[i];
        scale = std::sqrt(scale);
        s.converged = false;
        for (int it = 0; it < m_options.newton_max_iterations; ++it) {
            auto t = std::chrono::steady_clock::now();
            assemble(0.0, 1.0, system_output());
            if (!m_contact.empty() || !m_pairs.empty()) f_ext = external_force(); // contact forces follow the nodes
            Eigen::VectorXd rhs = f_ext - m_internal;
            apply_constraints(rhs);
            s.assembly_ms += ms_since(t);
            s.residual = scale > 0.0 ? rhs.norm() / scale : rhs.norm();
            if (s.residual <= m_options.cg_tolerance) {
                s.converged = true;
                break;
            }
            Eigen::VectorXd dx = Eigen::VectorXd::Zero(n);
            double cg_residual = 0.0;
            t = std::chrono::steady_clock::now();
            s.cg_iterations += solve(rhs, dx, cg_residual);
            s.solve_ms += ms_since(t);
            x += dx;
            m_element_pass_current = false;
            m_pairs.settle(m_x); // a contact only pushes
            ++s.newton_iterations;
        }
    }
    s.step_ms = ms_since(start);
    if (m_options.quasi_static && !m_integrator) // dynamic steps measured their end state for the energy check
        s.elastic_energy_j = elastic_energy();
    for (std::size_t i = 0; i < m_x.size(); ++i)
        s.max_displacement_m = std::max(s.max_displacement_m, (m_x[i] - m_model.rest_positions()[i]).norm());
    return s;
}

std::vector<Eigen::Vector3d> ImplicitSolver::response(const std::vector<Eigen::Vector3d>& load)
{
    if (m_integrator || load.size() != m_x.size()) return {};
    const auto n = static_cast<Eigen::Index>(3 * m_x.size());
    const double dt = m_options.dt_s;
    // The step's system at the current positions, its contact terms (the tools' springs, which
    // sit in series with what is measured, and the pairs') left out.
    // Nothing the steps read is left changed: the element rotations' warm start is put back and
    // the next step assembles its own pass, so a run measuring compliances steps bit for bit as
    // one that does not.
    const std::vector<Eigen::Quaterniond> rotation = m_rotation;
    const double contact_scale = std::exchange(m_contact_scale, 0.0);
    if (m_options.quasi_static) assemble(0.0, 1.0, system_output());
    else assemble(1.0 + dt * m_options.rayleigh_mass_per_s, dt * m_options.rayleigh_stiffness_s + dt * dt, system_output());
    Eigen::VectorXd rhs = Eigen::Map<const Eigen::VectorXd>(load.front().data(), n);
    apply_constraints(rhs);
    Eigen::VectorXd x = Eigen::VectorXd::Zero(n);
    double residual = 0.0;
    // Jacobi-preconditioned, to 1e-4 (the compliance, x'load, is accurate to about its square),
    // leaving the step's own preconditioner as it is.
    std::unique_ptr<Preconditioner> preconditioner = std::move(m_preconditioner);
    const SolverOptions options = m_options;
    m_options.cg_tolerance = 1e-4;
    m_options.cg_max_iterations = std::max(options.cg_max_iterations, 2000);
    solve(rhs, x, residual, true);
    m_options = options;
    m_preconditioner = std::move(preconditioner);
    m_contact_scale = contact_scale;
    m_rotation = rotation;
    m_element_pass_current = false;
    m_matrix_current = false;
    if (!(residual <= 1e-4) || !x.allFinite()) return {};
    if (!m_options.quasi_static) x *= dt * dt; // a velocity change per unit impulse dt: dt^2 of displacement
    std::vector<Eigen::Vector3d> out(m_x.size());
    for (std::size_t i = 0; i < out.size(); ++i) out[i] = x.segment<3>(static_cast<Eigen::Index>(3 * i));
    return out;
}

Eigen::Vector3d ImplicitSolver::momentum() const
{
    Eigen::VectorXd mv;
    mass_times(m_v, mv);
    Eigen::Vector3d p = Eigen::Vector3d::Zero();
    for (std::size_t n = 0; n < m_x.size(); ++n) p += mv.segment<3>(static_cast<Eigen::Index>(3 * n));
    return p;
}

} // namespace vox::fem
