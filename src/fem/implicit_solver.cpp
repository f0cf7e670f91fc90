#include "fem/implicit_solver.hpp"

#include "core/error.hpp"
#include "fem/corotation.hpp"


#include <algorithm>
#include <chrono>
#include <cmath>

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

ImplicitSolver::ImplicitSolver(const HexModel& model, const SolverOptions& options)
    : m_model(model), m_options(options)
{
    m_options.validate();
    const std::size_t n = model.node_count();
    m_x = model.rest_positions();
    m_v.assign(n, Eigen::Vector3d::Zero());
    m_external.assign(n, Eigen::Vector3d::Zero());
    m_fixed.assign(3 * n, 0);

    // The matrix pattern: 3 x 3 blocks for every pair of nodes sharing an element; each element
    // keeps the positions of its 576 entries so assembly is a plain accumulation.
    std::vector<Eigen::Triplet<double>> pattern;
    pattern.reserve(model.elements().size() * 576);
    for (const HexElement& e : model.elements())
        for (int c = 0; c < 8; ++c)
            for (int d = 0; d < 8; ++d)
                for (int i = 0; i < 3; ++i)
                    for (int j = 0; j < 3; ++j)
                        pattern.emplace_back(3 * static_cast<int>(e.dof_node[c]) + i, 3 * static_cast<int>(e.dof_node[d]) + j, 0.0);
    m_matrix.resize(static_cast<Eigen::Index>(3 * n), static_cast<Eigen::Index>(3 * n));
    m_matrix.setFromTriplets(pattern.begin(), pattern.end());
    m_matrix.makeCompressed();
    m_slot.resize(model.elements().size() * 576);
    const int* outer = m_matrix.outerIndexPtr();
    const int* inner = m_matrix.innerIndexPtr();
    std::size_t k = 0;
    for (const HexElement& e : model.elements())
        for (int c = 0; c < 8; ++c)
            for (int i = 0; i < 3; ++i) {
                const int row = 3 * static_cast<int>(e.dof_node[c]) + i;
                for (int d = 0; d < 8; ++d)
                    for (int j = 0; j < 3; ++j) {
                        const int col = 3 * static_cast<int>(e.dof_node[d]) + j;
                        m_slot[k++] = static_cast<int>(std::lower_bound(inner + outer[row], inner + outer[row + 1], col) - inner);
                    }
            }
    m_internal = Eigen::VectorXd::Zero(static_cast<Eigen::Index>(3 * n));
}

void ImplicitSolver::fix(std::uint32_t node, unsigned axes)
{
    for (int a = 0; a < 3; ++a)
        if (axes & (1u << a)) m_fixed[3 * node + static_cast<std::size_t>(a)] = 1;
}

double ImplicitSolver::assemble(double m_scale, double k_scale)
{
    std::fill(m_matrix.valuePtr(), m_matrix.valuePtr() + m_matrix.nonZeros(), 0.0);
    m_internal.setZero();
    double energy = 0.0;
    double* values = m_matrix.valuePtr();
    const auto& elements = m_model.elements();
    for (std::size_t e = 0; e < elements.size(); ++e) {
        const HexElement& el = elements[e];
        Eigen::Matrix3d f = Eigen::Matrix3d::Zero();
        for (int c = 0; c < 8; ++c) f += (m_x[el.dof_node[c]] - m_x[el.dof_node[0]]) * el.gradient.row(c);
        const Eigen::Matrix3d r = polar_rotation(f);
        // Displacements relative to corner 0: K ignores translations, and far from the origin
        // (a scan sits ~0.2 m away) subtracting them first keeps the small strains exact.
        const Eigen::Vector3d x0 = m_x[el.dof_node[0]];
        const Eigen::Vector3d rest0 = el.rest.segment<3>(0);
        Vector24d u;
        for (int c = 0; c < 8; ++c)
            u.segment<3>(3 * c) = r.transpose() * (m_x[el.dof_node[c]] - x0) - (el.rest.segment<3>(3 * c) - rest0);
        const Matrix24d& k = *el.stiffness;
        const Vector24d fl = k * u;
        energy += 0.5 * u.dot(fl);
        for (int c = 0; c < 8; ++c) m_internal.segment<3>(3 * el.dof_node[c]) += r * fl.segment<3>(3 * c);

        const int* slot = &m_slot[576 * e];
        for (int c = 0; c < 8; ++c)
            for (int d = 0; d < 8; ++d) {
                const Eigen::Matrix3d block = r * k.block<3, 3>(3 * c, 3 * d) * r.transpose();
                for (int i = 0; i < 3; ++i)
                    for (int j = 0; j < 3; ++j)
                        values[slot[24 * (3 * c + i) + 3 * d + j]] +=
                            k_scale * block(i, j) + (i == j ? m_scale * el.mass(c, d) : 0.0);
            }
    }
    if (m_scale != 0.0)
        for (std::size_t n = 0; n < m_x.size(); ++n)
            if (m_model.added_mass()[n] > 0.0)
                for (int i = 0; i < 3; ++i) {
                    const auto d = static_cast<Eigen::Index>(3 * n + static_cast<std::size_t>(i));
                    m_matrix.coeffRef(d, d) += m_scale * m_model.added_mass()[n];
                }
    return energy;
}

Eigen::VectorXd ImplicitSolver::external_force() const
{
    Eigen::VectorXd f(static_cast<Eigen::Index>(3 * m_x.size()));
    for (std::size_t n = 0; n < m_x.size(); ++n)
        f.segment<3>(static_cast<Eigen::Index>(3 * n)) = m_model.nodal_mass()[n] * m_gravity + m_external[n];
    return f;
}

void ImplicitSolver::apply_constraints(Eigen::VectorXd& rhs)
{
    // Held degrees of freedom: identity rows and columns, zero right-hand side.
    for (Eigen::Index row = 0; row < m_matrix.outerSize(); ++row)
        for (Eigen::SparseMatrix<double, Eigen::RowMajor>::InnerIterator it(m_matrix, row); it; ++it)
            if (m_fixed[static_cast<std::size_t>(row)] || m_fixed[static_cast<std::size_t>(it.col())])
                it.valueRef() = (row == it.col()) ? 1.0 : 0.0;
    for (Eigen::Index i = 0; i < rhs.size(); ++i)
        if (m_fixed[static_cast<std::size_t>(i)]) rhs[i] = 0.0;
}

int ImplicitSolver::solve(const Eigen::VectorXd& rhs, Eigen::VectorXd& x, double& residual)
{
    // Conjugate gradients on the Jacobi-scaled system D^-1/2 A D^-1/2 y = D^-1/2 b, x = D^-1/2 y,
    // stopping when the scaled residual falls below the tolerance relative to the scaled right-hand
    // side. Unscaled, nodes that carry almost no material (an element holding one voxel of 512)
    // would barely count in the residual and could move wildly while the solve "converges".
    const Eigen::Index n = rhs.size();
    Eigen::VectorXd inv_sqrt_d(n);
    for (Eigen::Index i = 0; i < n; ++i) {
        const double d = m_matrix.coeff(i, i);
        inv_sqrt_d[i] = d > 0.0 ? 1.0 / std::sqrt(d) : 1.0;
    }
    const double b_norm = rhs.cwiseProduct(inv_sqrt_d).norm();
    if (b_norm == 0.0) {
        x.setZero();
        residual = 0.0;
        return 0;
    }
    if (m_multigrid) m_multigrid->update(m_matrix, m_fixed);
    auto precondition = [&](const Eigen::VectorXd& res, Eigen::VectorXd& out) {
        if (m_multigrid)
            m_multigrid->apply(res, out);
        else
            out = res.cwiseProduct(inv_sqrt_d).cwiseProduct(inv_sqrt_d);
    };
    auto scaled_norm = [&](const Eigen::VectorXd& res) { return res.cwiseProduct(inv_sqrt_d).norm() / b_norm; };
    Eigen::VectorXd r = rhs - m_matrix * x;
    Eigen::VectorXd z(n);
    precondition(r, z);
    Eigen::VectorXd p = z, q(n);
    double rz = r.dot(z);
    int it = 0;
    residual = scaled_norm(r);
    while (residual > m_options.cg_tolerance && it < m_options.cg_max_iterations) {
        q.noalias() = m_matrix * p;
        const double pq = p.dot(q);
        if (!(pq > 0.0)) break; // not positive definite along p: stop rather than diverge
        const double alpha = rz / pq;
        x += alpha * p;
        r -= alpha * q;
        precondition(r, z);
        const double rz_next = r.dot(z);
        p = z + (rz_next / rz) * p;
        rz = rz_next;
        residual = scaled_norm(r);
        ++it;
    }
    return it;
}

StepStats ImplicitSolver::step()
{
    const auto start = std::chrono::steady_clock::now();
    StepStats s;
    const double dt = m_options.dt_s;
    const auto n = static_cast<Eigen::Index>(3 * m_x.size());
    const Eigen::VectorXd f_ext = external_force();
    Eigen::Map<Eigen::VectorXd> v(m_v.front().data(), n);
    Eigen::Map<Eigen::VectorXd> x(m_x.front().data(), n);

    if (!m_options.quasi_static) {
        assemble(1.0 + dt * m_options.rayleigh_mass_per_s, dt * m_options.rayleigh_stiffness_s + dt * dt);
        // M v from the element mass matrices (the assembled matrix holds M + dt C + dt^2 K).
        Eigen::VectorXd rhs = dt * (f_ext - m_internal);
        for (const HexElement& el : m_model.elements())
            for (int c = 0; c < 8; ++c)
                for (int d = 0; d < 8; ++d) rhs.segment<3>(3 * el.dof_node[c]) += el.mass(c, d) * m_v[el.dof_node[d]];
        for (std::size_t i = 0; i < m_x.size(); ++i)
            rhs.segment<3>(static_cast<Eigen::Index>(3 * i)) += m_model.added_mass()[i] * m_v[i];
        apply_constraints(rhs);
        Eigen::VectorXd next = v;
        for (Eigen::Index i = 0; i < n; ++i)
            if (m_fixed[static_cast<std::size_t>(i)]) next[i] = 0.0;
        s.cg_iterations = solve(rhs, next, s.residual);
        s.converged = s.residual <= m_options.cg_tolerance;
        v = next;
        x += dt * v;
    } else {
        v.setZero();
        double scale = 0.0;
        for (Eigen::Index i = 0; i < n; ++i)
            if (!m_fixed[static_cast<std::size_t>(i)]) scale += f_ext[i] * f_ext[i];
        scale = std::sqrt(scale);
        s.converged = false;
        for (int it = 0; it < m_options.newton_max_iterations; ++it) {
            assemble(0.0, 1.0);
            Eigen::VectorXd rhs = f_ext - m_internal;
            apply_constraints(rhs);
            s.residual = scale > 0.0 ? rhs.norm() / scale : rhs.norm();
            if (s.residual <= m_options.cg_tolerance) {
                s.converged = true;
                break;
            }
            Eigen::VectorXd dx = Eigen::VectorXd::Zero(n);
            double cg_residual = 0.0;
            s.cg_iterations += solve(rhs, dx, cg_residual);
            x += dx;
            ++s.newton_iterations;
        }
    }
    // Energies and displacement at the new state.
    s.elastic_energy_j = assemble(0.0, 0.0);
    for (const HexElement& el : m_model.elements())
        for (int c = 0; c < 8; ++c)
            for (int d = 0; d < 8; ++d) s.kinetic_energy_j += 0.5 * el.mass(c, d) * m_v[el.dof_node[c]].dot(m_v[el.dof_node[d]]);
    for (std::size_t i = 0; i < m_x.size(); ++i) s.kinetic_energy_j += 0.5 * m_model.added_mass()[i] * m_v[i].squaredNorm();
    for (std::size_t i = 0; i < m_x.size(); ++i)
        s.max_displacement_m = std::max(s.max_displacement_m, (m_x[i] - m_model.rest_positions()[i]).norm());
    s.step_ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
    return s;
}

Eigen::Vector3d ImplicitSolver::momentum() const
{
    Eigen::Vector3d p = Eigen::Vector3d::Zero();
    for (const HexElement& el : m_model.elements())
        for (int c = 0; c < 8; ++c)
            for (int d = 0; d < 8; ++d) p += el.mass(c, d) * m_v[el.dof_node[d]];
    for (std::size_t i = 0; i < m_x.size(); ++i) p += m_model.added_mass()[i] * m_v[i];
    return p;
}

} // namespace vox::fem
