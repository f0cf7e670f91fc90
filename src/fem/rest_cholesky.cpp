#include "fem/rest_cholesky.hpp"

namespace vox::fem {

RestCholesky::RestCholesky(const Eigen::Matrix3d& frame, int refactor_iterations)
    : m_frame(frame), m_refactor_iterations(refactor_iterations)
{
}

void RestCholesky::update(const SystemMatrix& a, const std::vector<unsigned char>& fixed,
                          const std::vector<Eigen::Quaterniond>& node_rotation)
{
    if (m_stale || m_fixed != fixed || m_factored_rotation.size() != node_rotation.size()) {
        const Eigen::SparseMatrix<double> column_major(a);
        // A singular K (nothing holds the object) may still factor, with pivots at round-off level:
        // that is a failure too.
        m_failed = !m_factor.factor(column_major, m_factorizations == 0 || m_fixed != fixed);
        ++m_factorizations;
        m_factored_rotation = node_rotation;
        m_fixed = fixed;
        m_stale = false;
    }
    // World-frame rotation of each node since the factorisation: F Q_now Q_factored^-1 F^T.
    m_warp.resize(node_rotation.size());
    for (std::size_t n = 0; n < node_rotation.size(); ++n)
        m_warp[n] = m_frame * (node_rotation[n] * m_factored_rotation[n].conjugate()).toRotationMatrix() * m_frame.transpose();
}

void RestCholesky::apply(const Eigen::VectorXd& r, Eigen::VectorXd& z) const
{
    m_scratch.resize(r.size());
    for (std::size_t n = 0; n < m_warp.size(); ++n) {
        const auto i = static_cast<Eigen::Index>(3 * n);
        m_scratch.segment<3>(i) = m_warp[n].transpose() * r.segment<3>(i);
    }
    for (Eigen::Index i = 0; i < r.size(); ++i)
        if (m_fixed[static_cast<std::size_t>(i)]) m_scratch[i] = 0.0;
    m_factor.solve(m_scratch);
    z.resize(r.size());
    for (std::size_t n = 0; n < m_warp.size(); ++n) {
        const auto i = static_cast<Eigen::Index>(3 * n);
        z.segment<3>(i) = m_warp[n] * m_scratch.segment<3>(i);
    }
    for (Eigen::Index i = 0; i < r.size(); ++i)
        if (m_fixed[static_cast<std::size_t>(i)]) z[i] = 0.0;
}

} // namespace vox::fem
