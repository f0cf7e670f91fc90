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

Eigen::Matrix3d deformation_gradient(const std::array<Eigen::Vector3d, 4>& p, const TetGeometry& g)
{
    Eigen::Matrix3d f = Eigen::Matrix3d::Zero();
    for (int c = 1; c < 4; ++c) f.noalias() += (p[static_cast<std::size_t>(c)] - p[0]) * g.gradient.row(c);
    return f;
}

} // namespace

void XfemOptions::validate() const
{
    if (!(dt_s > 0.0) || !std::isfinite(dt_s)) throw InputError("isxfem solver: dt_s must be positive");
    if (!(cg_tolerance > 0.0 && cg_tolerance < 1.0)) throw InputError("isxfem solver: cg_tolerance must be in (0, 1)");
    if (cg_max_iterations < 1) throw InputError("isxfem solver: cg_max_iterations must be at least 1");
    if (!(rayleigh_mass_per_s >= 0.0) || !(rayleigh_stiffness_s >= 0.0)) throw InputError("isxfem solver: Rayleigh damping must be >= 0");
}

XfemSolver::XfemSolver(const XfemModel& model, const XfemOptions& options) : m_model(model), m_options(options)
{
    m_options.validate();
    m_x = model.mesh().nodes;
    m_v.assign(m_x.size(), Eigen::Vector3d::Zero());
    m_fixed.assign(3 * m_x.size(), 0);
    model_changed();
}

void XfemSolver::fix(std::uint32_t node, unsigned axes)
{
    for (unsigned a = 0; a < 3; ++a)
        if (axes & (1u << a)) m_fixed.at(3 * std::size_t{node} + a) = 1;
    if (m_preconditioner) m_preconditioner->invalidate();
}

void XfemSolver::set_preconditioner(std::unique_ptr<fem::Preconditioner> p) { m_preconditioner = std::move(p); }

void XfemSolver::update_block_rotations()
{
    std::vector<Eigen::Vector4d> sum(m_x.size(), Eigen::Vector4d::Zero());
    const auto& elements = m_model.elements();
    for (std::size_t e = 0; e < elements.size(); ++e) {
        const XfemElement& el = elements[e];
        for (std::size_t side = 0; side < (el.cut >= 0 ? 2u : 1u); ++side)
            for (std::size_t a = 0; a < el.block_count(); ++a) fem::accumulate_rotation(sum[el.block(a)], m_rotation[e][side]);
    }
    m_block_rotation.resize(m_x.size(), Eigen::Quaterniond::Identity());
    for (std::size_t b = 0; b < m_x.size(); ++b)
        if (sum[b].squaredNorm() > 0.0) m_block_rotation[b].coeffs() = sum[b].normalized();
}

void XfemSolver::model_changed()
{
    const std::size_t blocks = m_model.block_count();
    m_x.resize(blocks, Eigen::Vector3d::Zero());
    m_v.resize(blocks, Eigen::Vector3d::Zero());
    m_fixed.resize(3 * blocks, 0);
    const auto& elements = m_model.elements();
    m_rotation.resize(elements.size(), {Eigen::Quaterniond::Identity(), Eigen::Quaterniond::Identity()});
    m_was_cut.resize(elements.size(), 0);
    for (std::size_t e = 0; e < elements.size(); ++e)
        if (elements[e].cut >= 0 && !m_was_cut[e]) { // a newly cut element: both sides start from its rotation
            m_rotation[e][1] = m_rotation[e][0];
            m_was_cut[e] = 1;
        }
    build_pattern();
    if (m_preconditioner) m_preconditioner->invalidate(); // a grown system: factor it anew
    m_preconditioner_failed = false;
}

void XfemSolver::build_pattern()
{
    // A 3 x 3 block for every pair of dof blocks sharing an element; the row of dof 3A + i holds
    // the columns of A's neighbours B in order, 3 each, so an entry sits at
    // outer[3A + i] + 3 rank(A, B) + j.
    const auto& elements = m_model.elements();
    const std::size_t blocks = m_model.block_count();
    std::vector<std::vector<std::uint32_t>> neighbours(blocks);
    for (const XfemElement& e : elements)
        for (std::size_t a = 0; a < e.block_count(); ++a)
            for (std::size_t b = 0; b < e.block_count(); ++b) neighbours[e.block(a)].push_back(e.block(b));
    for (std::uint32_t a = 0; a < blocks; ++a) {
        auto& list = neighbours[a];
        list.push_back(a); // a block no element touches still gets its diagonal
        std::sort(list.begin(), list.end());
        list.erase(std::unique(list.begin(), list.end()), list.end());
    }
    std::size_t entries = 0;
    for (const auto& list : neighbours) entries += 9 * list.size();
    m_matrix.resize(static_cast<Eigen::Index>(3 * blocks), static_cast<Eigen::Index>(3 * blocks));
    m_matrix.resizeNonZeros(static_cast<Eigen::Index>(entries));
    int* outer = m_matrix.outerIndexPtr();
    int* inner = m_matrix.innerIndexPtr();
    outer[0] = 0;
    for (std::size_t a = 0; a < blocks; ++a)
        for (std::size_t i = 0; i < 3; ++i) {
            int position = outer[3 * a + i];
            for (std::uint32_t b : neighbours[a])
                for (int j = 0; j < 3; ++j) inner[position++] = 3 * static_cast<int>(b) + j;
            outer[3 * a + i + 1] = position;
        }
    m_rank_start.assign(elements.size() + 1, 0);
    m_rank.clear();
    for (std::size_t e = 0; e < elements.size(); ++e) {
        const XfemElement& el = elements[e];
        for (std::size_t a = 0; a < el.block_count(); ++a)
            for (std::size_t b = 0; b < el.block_count(); ++b) {
                const auto& list = neighbours[el.block(a)];
                m_rank.push_back(static_cast<std::uint32_t>(std::lower_bound(list.begin(), list.end(), el.block(b)) - list.begin()));
            }
        m_rank_start[e + 1] = static_cast<std::uint32_t>(m_rank.size());
    }
    // The consistent mass, constant between cuts.
    std::fill(m_matrix.valuePtr(), m_matrix.valuePtr() + m_matrix.nonZeros(), 0.0);
    for (std::size_t e = 0; e < elements.size(); ++e) {
        const XfemElement& el = elements[e];
        const std::size_t n = el.block_count();
        for (std::size_t a = 0; a < n; ++a)
            for (std::size_t b = 0; b < n; ++b) {
                const std::uint32_t row = 3 * el.block(a), rank = m_rank[m_rank_start[e] + a * n + b];
                const double m = el.mass(static_cast<Eigen::Index>(3 * a), static_cast<Eigen::Index>(3 * b));
                for (std::uint32_t i = 0; i < 3; ++i) m_matrix.valuePtr()[outer[row + i] + 3 * static_cast<int>(rank) + static_cast<int>(i)] += m;
            }
    }
    m_mass = m_matrix;
    m_internal = Eigen::VectorXd::Zero(static_cast<Eigen::Index>(3 * blocks));
}

void XfemSolver::assemble(double scale_m, double scale_k)
{
    const auto& elements = m_model.elements();
    const auto& rest = m_model.mesh().nodes;
    double* values = m_matrix.valuePtr();
    const double* mass = m_mass.valuePtr();
    for (Eigen::Index i = 0; i < m_matrix.nonZeros(); ++i) values[i] = scale_m * mass[i];
    m_internal.setZero();
    const int* outer = m_matrix.outerIndexPtr();
    // Adds scale_k Rb K Rb^T (Rb: r on every block) and the force Rb K (Rb^T q - q_rest).
    auto add = [&](std::size_t e, const auto& k, const Eigen::Matrix3d& r, const auto& local) {
        const XfemElement& el = elements[e];
        const std::size_t n = el.block_count();
        const auto f = (k * local).eval();
        for (std::size_t a = 0; a < n; ++a) {
            m_internal.segment<3>(3 * static_cast<Eigen::Index>(el.block(a))) += r * f.template segment<3>(3 * static_cast<Eigen::Index>(a));
            for (std::size_t b = 0; b < n; ++b) {
                const Eigen::Matrix3d block =
                    scale_k * r * k.template block<3, 3>(3 * static_cast<Eigen::Index>(a), 3 * static_cast<Eigen::Index>(b)) * r.transpose();
                const std::uint32_t row = 3 * el.block(a), rank = m_rank[m_rank_start[e] + a * n + b];
                for (int i = 0; i < 3; ++i)
                    for (int j = 0; j < 3; ++j) values[outer[row + static_cast<std::uint32_t>(i)] + 3 * static_cast<int>(rank) + j] += block(i, j);
            }
        }
    };
    for (std::size_t e = 0; e < elements.size(); ++e) {
        const XfemElement& el = elements[e];
        std::array<Eigen::Vector3d, 4> x{};
        for (std::size_t c = 0; c < 4; ++c) x[c] = m_x[el.node[c]];
        if (el.cut < 0) {
            fem::extract_rotation(deformation_gradient(x, el.geometry), m_rotation[e][0]);
            const Eigen::Matrix3d r = m_rotation[e][0].toRotationMatrix();
            Eigen::Matrix<double, 12, 1> u;
            for (std::size_t c = 0; c < 4; ++c)
                u.segment<3>(3 * static_cast<Eigen::Index>(c)) = r.transpose() * (x[c] - x[0]) - (rest[el.node[c]] - rest[el.node[0]]);
            add(e, el.stiffness, r, u);
            continue;
        }
        for (std::size_t side = 0; side < 2; ++side) {
            // The side's linear field: nodal positions x_i + (h - H_i) a_i.
            std::array<Eigen::Vector3d, 4> p{};
            for (std::size_t c = 0; c < 4; ++c)
                p[c] = x[c] + (static_cast<double>(side) - el.node_side[c]) * m_x[el.enriched[c]];
            fem::extract_rotation(deformation_gradient(p, el.geometry), m_rotation[e][side]);
            const Eigen::Matrix3d r = m_rotation[e][side].toRotationMatrix();
            Eigen::Matrix<double, 24, 1> u;
            for (std::size_t c = 0; c < 4; ++c) {
                u.segment<3>(3 * static_cast<Eigen::Index>(c)) = r.transpose() * (x[c] - x[0]) - (rest[el.node[c]] - rest[el.node[0]]);
                u.segment<3>(12 + 3 * static_cast<Eigen::Index>(c)) = r.transpose() * m_x[el.enriched[c]];
            }
            add(e, el.side_stiffness[side], r, u);
        }
    }
    // Held dofs: identity rows and columns.
    for (Eigen::Index row = 0; row < m_matrix.outerSize(); ++row)
        for (Matrix::InnerIterator it(m_matrix, row); it; ++it)
            if (m_fixed[static_cast<std::size_t>(row)] || m_fixed[static_cast<std::size_t>(it.col())])
                it.valueRef() = row == it.col() ? 1.0 : 0.0;
}

void XfemSolver::multiply(const Eigen::VectorXd& p, Eigen::VectorXd& out) const
{
    out.noalias() = m_matrix * p;
}

int XfemSolver::solve(const Eigen::VectorXd& rhs, Eigen::VectorXd& x, double& residual)
{
    Eigen::VectorXd inv_d = m_matrix.diagonal();
    for (Eigen::Index i = 0; i < inv_d.size(); ++i) inv_d[i] = inv_d[i] > 0.0 ? 1.0 / inv_d[i] : 1.0;
    const bool factor = m_preconditioner && !m_preconditioner_failed;
    if (factor) {
        update_block_rotations();
        m_preconditioner->update(&m_matrix, m_fixed, m_block_rotation);
        if (m_preconditioner->failed()) { // a (nearly) singular system: Jacobi carries on until the next cut
            m_preconditioner_failed = true;
            m_fallback_note = std::string(m_preconditioner->name()) + " preconditioner failed (a nearly singular system); Jacobi took over";
        }
    }
    auto precondition = [&](const Eigen::VectorXd& res, Eigen::VectorXd& out) {
        if (m_preconditioner && !m_preconditioner_failed)
            m_preconditioner->apply(res, out);
        else
            out = res.cwiseProduct(inv_d);
    };
    const fem::CgResult cg = fem::conjugate_gradient([this](const Eigen::VectorXd& p, Eigen::VectorXd& out) { multiply(p, out); },
                                                     precondition, rhs, inv_d.cwiseSqrt(), m_options.cg_tolerance,
                                                     m_options.cg_max_iterations, x);
    residual = cg.residual;
    if (m_preconditioner && !m_preconditioner_failed) m_preconditioner->report_iterations(cg.iterations);
    return cg.iterations;
}

XfemStepStats XfemSolver::step()
{
    const auto start = std::chrono::steady_clock::now();
    XfemStepStats s;
    const double dt = m_options.dt_s;
    const auto n = static_cast<Eigen::Index>(dof_count());
    assemble(1.0 + dt * m_options.rayleigh_mass_per_s, dt * m_options.rayleigh_stiffness_s + dt * dt);
    Eigen::Map<Eigen::VectorXd> v(m_v.front().data(), n);
    Eigen::VectorXd g = Eigen::VectorXd::Zero(n); // gravity acts through the nodes' own shape functions
    for (std::size_t b = 0; b < m_model.node_count(); ++b) g.segment<3>(3 * static_cast<Eigen::Index>(b)) = m_gravity;
    Eigen::VectorXd rhs = m_mass * v + dt * (m_mass * g - m_internal);
    Eigen::VectorXd next = v;
    for (Eigen::Index i = 0; i < n; ++i)
        if (m_fixed[static_cast<std::size_t>(i)]) rhs[i] = next[i] = 0.0;
    s.assembly_ms = ms_since(start);
    const auto t = std::chrono::steady_clock::now();
    s.cg_iterations = solve(rhs, next, s.residual);
    s.converged = s.residual <= m_options.cg_tolerance;
    s.solve_ms = ms_since(t);
    v = next;
    Eigen::Map<Eigen::VectorXd>(m_x.front().data(), n) += dt * v;
    s.kinetic_energy_j = kinetic_energy();
    s.step_ms = ms_since(start);
    return s;
}

Eigen::Vector3d XfemSolver::position(std::size_t t, const std::array<double, 4>& n, int side) const
{
    const XfemElement& el = m_model.elements()[t];
    Eigen::Vector3d p = Eigen::Vector3d::Zero();
    for (std::size_t c = 0; c < 4; ++c) p += n[c] * m_x[el.node[c]];
    if (el.cut < 0) return p;
    double gamma = 0.0;
    for (std::size_t c = 0; c < 4; ++c) gamma += n[c] * el.node_side[c];
    const double k = m_model.k();
    for (std::size_t c = 0; c < 4; ++c) {
        const double psi = side - (k * gamma + (1.0 - k) * el.node_side[c]);
        p += psi * n[c] * m_x[el.enriched[c]];
    }
    return p;
}

double XfemSolver::kinetic_energy() const
{
    const Eigen::Map<const Eigen::VectorXd> v(m_v.front().data(), static_cast<Eigen::Index>(dof_count()));
    return 0.5 * v.dot(m_mass * v);
}

Eigen::Vector3d XfemSolver::momentum() const
{
    const Eigen::Map<const Eigen::VectorXd> v(m_v.front().data(), static_cast<Eigen::Index>(dof_count()));
    const Eigen::VectorXd mv = m_mass * v;
    Eigen::Vector3d p = Eigen::Vector3d::Zero();
    for (std::size_t b = 0; b < m_model.node_count(); ++b) p += mv.segment<3>(3 * static_cast<Eigen::Index>(b));
    return p;
}

} // namespace vox::isxfem
