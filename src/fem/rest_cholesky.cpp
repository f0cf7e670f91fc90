#include "fem/rest_cholesky.hpp"

#include <stdexcept>

namespace vox::fem {

RestCholesky::RestCholesky(const Eigen::Matrix3d& frame, int refactor_iterations)
    : m_frame(frame), m_refactor_iterations(refactor_iterations)
{
}

void RestCholesky::update(const SystemMatrix* a, const std::vector<unsigned char>& fixed,
                          const std::vector<Eigen::Quaterniond>& node_rotation)
{
    if (m_stale || m_fixed != fixed || m_factored_rotation.size() != node_rotation.size()) {
        if (!a) throw std::logic_error("RestCholesky::update: a new factor needs the assembled matrix");
        const Eigen::SparseMatrix<double> column_major(*a);
        const bool new_pattern = m_factorizations == 0 || m_fixed != fixed || a->rows() != m_rows || a->nonZeros() != m_nonzeros;
        m_rows = a->rows();
        m_nonzeros = a->nonZeros();
        // A singular K (nothing holds the object) may still factor, with pivots at round-off level:
        // that is a failure too.
        m_failed = !m_factor.factor(column_major, new_pattern);
        ++m_factorizations;
        m_factored_rotation = node_rotation;
        m_fixed = fixed;
        m_stale = false;
        // A CG iteration streams the factor twice (2 flops an entry each way) and multiplies by
        // the matrix once (2 flops a non-zero). The factorisation's flops run in small dense
        // blocks at about half the solve's rate per flop (measured on the liver at level 4: 380
        // Mflop in 57 ms against 5.8 Mflop in 0.45 ms), hence the factor 2.
        const double iteration_flops = 4.0 * static_cast<double>(m_factor.entries()) + 2.0 * static_cast<double>(a->nonZeros());
        m_refactor_cost = 2.0 * m_factor.factor_flops() / iteration_flops;
        m_baseline = -1;
        m_excess = 0.0;
    }
    // World-frame rotation of each block since the factorisation: F Q_now Q_factored^-1 F^T.
    m_warp.resize(node_rotation.size());
    for (std::size_t n = 0; n < node_rotation.size(); ++n)
        m_warp[n] = m_frame * (node_rotation[n] * m_factored_rotation[n].conjugate()).toRotationMatrix() * m_frame.transpose();
    m_jump_warp.resize(m_jumps.size());
    for (std::size_t j = 0; j < m_jumps.size(); ++j)
        m_jump_warp[j] = m_jumps[j].sign * (m_warp[m_jumps[j].block] - m_warp[m_jumps[j].node]);
}

void RestCholesky::report_iterations(int iterations)
{
    if (m_baseline < 0 || iterations < m_baseline) m_baseline = iterations;
    m_excess += iterations - m_baseline;
    m_stale = m_stale || iterations > m_refactor_iterations || m_excess >= m_refactor_cost;
}

void RestCholesky::apply(const Eigen::VectorXd& r, Eigen::VectorXd& z) const
{
    // z = W A_0^-1 W^T r, W the warp with its jump couplings.
    m_scratch.resize(r.size());
    for (std::size_t n = 0; n < m_warp.size(); ++n) {
        const auto i = static_cast<Eigen::Index>(3 * n);
        m_scratch.segment<3>(i) = m_warp[n].transpose() * r.segment<3>(i);
    }
    for (std::size_t j = 0; j < m_jumps.size(); ++j)
        m_scratch.segment<3>(3 * static_cast<Eigen::Index>(m_jumps[j].node)) +=
            m_jump_warp[j].transpose() * r.segment<3>(3 * static_cast<Eigen::Index>(m_jumps[j].block));
    for (Eigen::Index i = 0; i < r.size(); ++i)
        if (m_fixed[static_cast<std::size_t>(i)]) m_scratch[i] = 0.0;
    m_factor.solve(m_scratch);
    z.resize(r.size());
    for (std::size_t n = 0; n < m_warp.size(); ++n) {
        const auto i = static_cast<Eigen::Index>(3 * n);
        z.segment<3>(i) = m_warp[n] * m_scratch.segment<3>(i);
    }
    for (std::size_t j = 0; j < m_jumps.size(); ++j)
        z.segment<3>(3 * static_cast<Eigen::Index>(m_jumps[j].block)) +=
            m_jump_warp[j] * m_scratch.segment<3>(3 * static_cast<Eigen::Index>(m_jumps[j].node));
    for (std::size_t i = 0; i < m_fixed.size(); ++i)
        if (m_fixed[i]) z[static_cast<Eigen::Index>(i)] = 0.0;
}

} // namespace vox::fem
