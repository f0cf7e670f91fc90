#include "isxfem/xfem_solver.hpp"

#include "core/error.hpp"
#include "fem/conjugate_gradient.hpp"
#include "fem/corotation.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <stdexcept>

namespace vox::isxfem {
namespace {

double ms_since(std::chrono::steady_clock::time_point t)
{
    return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t).count();
}

} // namespace

void XfemOptions::validate() const
{
    if (!(dt_s > 0.0) || !std::isfinite(dt_s)) throw InputError("isxfem solver: dt_s must be positive");
    if (!(cg_tolerance > 0.0 && cg_tolerance < 1.0)) throw InputError("isxfem solver: cg_tolerance must be in (0, 1)");
    if (cg_max_iterations < 1) throw InputError("isxfem solver: cg_max_iterations must be at least 1");
    if (!(rayleigh_mass_per_s >= 0.0) || !(rayleigh_stiffness_s >= 0.0)) throw InputError("isxfem solver: Rayleigh damping must be >= 0");
    if (!(regularisation_lambda >= 0.0) || !std::isfinite(regularisation_lambda))
        throw InputError("isxfem solver: regularisation_lambda must be >= 0");
    if (!(regularisation_threshold >= 0.0 && regularisation_threshold <= 1.0))
        throw InputError("isxfem solver: regularisation_threshold must be in [0, 1]");
}

XfemSolver::XfemSolver(const XfemModel& model, const XfemOptions& options) : m_model(model), m_options(options), m_operator(model)
{
    m_options.validate();
    m_x = model.mesh().nodes;
    m_v.assign(m_x.size(), Eigen::Vector3d::Zero());
    m_fixed.assign(3 * m_x.size(), 0);
    model_changed();
}

void XfemSolver::set_state(std::vector<Eigen::Vector3d> x, std::vector<Eigen::Vector3d> v)
{
    if (x.size() != m_model.block_count() || v.size() != x.size())
        throw std::invalid_argument("XfemSolver::set_state: " + std::to_string(x.size()) + " blocks given, the model has " +
                                    std::to_string(m_model.block_count()));
    m_x = std::move(x);
    m_v = std::move(v);
    m_previous_v.resize(0); // no extrapolation from before the jump
}

void XfemSolver::fix(std::uint32_t node, unsigned axes)
{
    for (unsigned a = 0; a < 3; ++a)
        if (axes & (1u << a)) m_fixed.at(3 * std::size_t{node} + a) = 1;
    if (m_preconditioner) m_preconditioner->invalidate();
}

void XfemSolver::set_preconditioner(std::unique_ptr<fem::Preconditioner> p)
{
    m_preconditioner = std::move(p);
    if (m_preconditioner) m_preconditioner->set_jump_blocks(m_jumps);
}

void XfemSolver::model_changed()
{
    const std::size_t blocks = m_model.block_count();
    const auto& elements = m_model.elements();
    m_x.resize(blocks, Eigen::Vector3d::Zero());
    m_v.resize(blocks, Eigen::Vector3d::Zero());
    m_fixed.resize(3 * blocks, 0);
    const std::vector<std::uint32_t> changed = m_operator.model_changed();
    m_regularised.clear();
    if (m_options.regularisation_lambda > 0.0)
        for (auto b = static_cast<std::uint32_t>(m_model.node_count()); b < blocks; ++b)
            if (m_model.volume_ratio(b) < m_options.regularisation_threshold) m_regularised.push_back(b);
    m_jumps.clear();
    std::vector<unsigned char> seen(blocks, 0);
    for (const XfemElement& el : elements)
        for (const ElementCut& cut : el.cuts)
            for (std::size_t c = 0; c < 4; ++c)
                if (!seen[cut.enriched[c]]) {
                    seen[cut.enriched[c]] = 1;
                    m_jumps.push_back({cut.enriched[c], el.node[c], cut.node_side[c] ? -1.0 : 1.0});
                }
    if (m_preconditioner) {
        m_preconditioner->set_jump_blocks(m_jumps);
        m_preconditioner->blocks_changed(changed);
        if (m_preconditioner_failed) m_preconditioner->invalidate();
    }
    m_preconditioner_failed = false;
}

int XfemSolver::solve(const Eigen::VectorXd& rhs, Eigen::VectorXd& x, double& residual, bool same_system)
{
    const double contact_scale = m_options.dt_s * m_options.dt_s;
    Eigen::VectorXd inv_d = m_operator.diagonal();
    m_pairs.add_diagonal(contact_scale, inv_d, &m_pair_in_matrix); // those in the matrix are in its diagonal
    for (Eigen::Index i = 0; i < inv_d.size(); ++i)
        inv_d[i] = m_fixed[static_cast<std::size_t>(i)] || !(inv_d[i] > 0.0) ? 1.0 : 1.0 / inv_d[i];
    const bool factor = m_preconditioner && !m_preconditioner_failed && !same_system;
    if (factor) {
        m_operator.block_rotations(m_block_rotation);
        m_preconditioner->update(&m_operator.matrix(), m_fixed, m_block_rotation);
        if (m_preconditioner->failed()) { // Jacobi carries on until the next cut
            m_preconditioner_failed = true;
            const fem::FactorFailure failure = m_preconditioner->failure();
            // An enriched block's dofs are a jump, not a place: its node is named.
            const Eigen::Vector3d* where = nullptr;
            if (failure.dof >= 0) {
                auto block = static_cast<std::uint32_t>(failure.dof / 3);
                if (block >= m_model.node_count()) block = m_model.enriched_node(block);
                where = &m_x[block];
            }
            m_fallback_note = fem::fallback_note(m_preconditioner->name(), failure, where, false, true);
        }
    }
    auto precondition = [&](const Eigen::VectorXd& res, Eigen::VectorXd& out) {
        if (m_preconditioner && !m_preconditioner_failed)
            m_preconditioner->apply(res, out);
        else
            out = res.cwiseProduct(inv_d);
    };
    // Pair contacts couple blocks the matrix's pattern may not join (two pieces): added to its product.
    const auto multiply = [&](const Eigen::VectorXd& p, Eigen::VectorXd& out) {
        m_operator.multiply(p, out);
        m_pairs.add_product(p, contact_scale, m_fixed, out, &m_pair_in_matrix);
    };
    const fem::CgResult cg = fem::conjugate_gradient(multiply,
                                                     precondition, rhs, inv_d.cwiseSqrt(), m_options.cg_tolerance,
                                                     m_options.cg_max_iterations, x);
    residual = cg.residual;
    if (m_preconditioner && !m_preconditioner_failed && !same_system) m_preconditioner->report_iterations(cg.iterations);
    return cg.iterations;
}

XfemStepStats XfemSolver::step()
{
    const auto start = std::chrono::steady_clock::now();
    XfemStepStats s;
    const double dt = m_options.dt_s;
    const auto n = static_cast<Eigen::Index>(dof_count());
    m_operator.update(m_x, m_fixed, 1.0 + dt * m_options.rayleigh_mass_per_s, dt * m_options.rayleigh_stiffness_s + dt * dt);
    const double shift = m_regularised.empty() ? 0.0 : m_operator.add_to_diagonal(m_regularised, m_options.regularisation_lambda);
    Eigen::Map<Eigen::VectorXd> v(m_v.front().data(), n);
    // Gravity acts through the nodes' own shape functions: the right-hand side is
    // M (v + dt g) - dt f_int.
    Eigen::VectorXd moved = v;
    for (std::size_t b = 0; b < m_model.node_count(); ++b) moved.segment<3>(3 * static_cast<Eigen::Index>(b)) += dt * m_gravity;
    Eigen::VectorXd rhs;
    m_operator.mass_multiply(moved, rhs);
    rhs -= dt * m_operator.internal_force();
    // Point loads (tool contact) act through the interpolation at their points, implicitly:
    // f(x') ~ f - S (x' - x) adds dt f to the right-hand side and dt^2 w_a w_b S to the matrix.
    for (const PointLoad& l : m_loads) {
        const XfemElement& el = m_model.elements()[l.tet];
        const std::array<double, k_max_blocks> w = weights(l.tet, l.bary, l.side);
        for (std::size_t a = 0; a < el.block_count(); ++a) rhs.segment<3>(3 * static_cast<Eigen::Index>(el.block(a))) += dt * w[a] * l.force_n;
        m_operator.add_point_stiffness(l.tet, w, dt * dt * l.stiffness_n_per_m);
    }
    // The regularisation as added inertia, (A + lambda I) v' = c + lambda v: it resists changes of
    // the small jumps' velocities, not the velocities themselves, so it conditions the system
    // without holding a jump that is already opening.
    for (std::uint32_t b : m_regularised) rhs.segment<3>(3 * static_cast<Eigen::Index>(b)) += shift * v.segment<3>(3 * static_cast<Eigen::Index>(b));
    Eigen::VectorXd next = v;
    if (m_previous_v.size() == n) next += v - m_previous_v; // CG starts from the velocity extrapolated (one iteration fewer at the median)
    // Pair contacts (obstacles, pieces) in the matrix where its pattern joins their blocks, so
    // that the factor sees them; the others are added to its product.
    m_pair_in_matrix.assign(m_pairs.pairs().size(), 0);
    for (std::size_t i = 0; i < m_pairs.pairs().size(); ++i) m_pair_in_matrix[i] = m_operator.add_pair_stiffness(m_pairs.pairs()[i], dt * dt);
    Eigen::VectorXd contact = Eigen::VectorXd::Zero(n);
    m_pairs.add_forces(m_x, contact);
    rhs += dt * contact;
    for (Eigen::Index i = 0; i < n; ++i)
        if (m_fixed[static_cast<std::size_t>(i)]) rhs[i] = next[i] = 0.0;
    s.assembly_ms = ms_since(start);
    const auto t = std::chrono::steady_clock::now();
    s.cg_iterations = solve(rhs, next, s.residual);
    // A pair contact that would pull two parting sides together at the step's end lets go, the
    // waiting ones that end pressed in join, and the step is solved again (from the last answer),
    // until nothing changes.
    for (int pass = 0; pass < fem::k_release_passes && !m_pairs.empty(); ++pass) {
        const std::vector<Eigen::Vector3d> end = m_pairs.step_end(m_x, dt, next);
        const std::vector<std::size_t> pulling = m_pairs.pulling(end), arriving = m_pairs.arriving(end);
        if (pulling.empty() && arriving.empty()) break;
        for (std::size_t i : pulling)
            if (m_pair_in_matrix[i]) m_operator.add_pair_stiffness(m_pairs.pairs()[i], -dt * dt);
        m_pairs.release(pulling);
        m_pairs.activate(arriving);
        for (std::size_t i : arriving) m_pair_in_matrix[i] = m_operator.add_pair_stiffness(m_pairs.pairs()[i], dt * dt);
        rhs -= dt * contact;
        contact.setZero();
        m_pairs.add_forces(m_x, contact);
        rhs += dt * contact;
        for (Eigen::Index i = 0; i < n; ++i)
            if (m_fixed[static_cast<std::size_t>(i)]) rhs[i] = 0.0;
        s.cg_iterations += solve(rhs, next, s.residual, true);
    }
    s.converged = s.residual <= m_options.cg_tolerance;
    s.solve_ms = ms_since(t);
    m_previous_v = v;
    v = next;
    Eigen::Map<Eigen::VectorXd>(m_x.front().data(), n) += dt * v;
    s.kinetic_energy_j = kinetic_energy();
    s.step_ms = ms_since(start);
    return s;
}

std::array<double, k_max_blocks> XfemSolver::weights(std::size_t t, const std::array<double, 4>& n, int region) const
{
    const XfemElement& el = m_model.elements()[t];
    std::array<double, k_max_blocks> w{};
    for (std::size_t c = 0; c < 4; ++c) w[c] = n[c];
    const double k = m_model.k();
    for (std::size_t j = 0; j < el.cuts.size(); ++j) {
        const ElementCut& cut = el.cuts[j];
        double gamma = 0.0;
        for (std::size_t c = 0; c < 4; ++c) gamma += n[c] * cut.node_side[c];
        const double h = (static_cast<unsigned>(region) >> j) & 1u;
        for (std::size_t c = 0; c < 4; ++c) w[4 + 4 * j + c] = (h - (k * gamma + (1.0 - k) * cut.node_side[c])) * n[c]; // psi_jc N_c
    }
    return w;
}

Eigen::Vector3d XfemSolver::interpolate(std::size_t t, const std::array<double, 4>& n, int region,
                                        const std::vector<Eigen::Vector3d>& blocks) const
{
    const XfemElement& el = m_model.elements()[t];
    const std::array<double, k_max_blocks> w = weights(t, n, region);
    Eigen::Vector3d out = Eigen::Vector3d::Zero();
    for (std::size_t a = 0; a < el.block_count(); ++a) out += w[a] * blocks[el.block(a)];
    return out;
}

void XfemSolver::set_point_loads(std::vector<PointLoad> loads)
{
    for (const PointLoad& l : loads)
        if (l.tet >= m_model.elements().size()) throw std::out_of_range("XfemSolver::set_point_loads: no tetrahedron " + std::to_string(l.tet));
    m_loads = std::move(loads);
}

double XfemSolver::kinetic_energy() const
{
    const Eigen::Map<const Eigen::VectorXd> v(m_v.front().data(), static_cast<Eigen::Index>(dof_count()));
    Eigen::VectorXd mv;
    m_operator.mass_multiply(v, mv);
    return 0.5 * v.dot(mv);
}

Eigen::Vector3d XfemSolver::momentum() const
{
    const Eigen::Map<const Eigen::VectorXd> v(m_v.front().data(), static_cast<Eigen::Index>(dof_count()));
    Eigen::VectorXd mv;
    m_operator.mass_multiply(v, mv);
    Eigen::Vector3d p = Eigen::Vector3d::Zero();
    for (std::size_t b = 0; b < m_model.node_count(); ++b) p += mv.segment<3>(3 * static_cast<Eigen::Index>(b));
    return p;
}

} // namespace vox::isxfem
