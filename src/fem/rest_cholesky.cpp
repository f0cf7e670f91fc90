#include "fem/rest_cholesky.hpp"

#include <algorithm>
#include <stdexcept>

namespace vox::fem {

RestCholesky::RestCholesky(const Eigen::Matrix3d& frame, int refactor_iterations)
    : m_frame(frame), m_refactor_iterations(refactor_iterations)
{
}

bool RestCholesky::same_holds(const std::vector<unsigned char>& fixed) const
{
    return fixed.size() >= m_fixed.size() && std::equal(m_fixed.begin(), m_fixed.end(), fixed.begin()) &&
           std::all_of(fixed.begin() + static_cast<std::ptrdiff_t>(m_fixed.size()), fixed.end(), [](unsigned char f) { return f == 0; });
}

void RestCholesky::refactor(const SystemMatrix& a, const std::vector<unsigned char>& fixed, const std::vector<Eigen::Quaterniond>& node_rotation)
{
    const Eigen::SparseMatrix<double> column_major(a);
    const bool new_pattern = m_factorizations == 0 || m_fixed != fixed || a.rows() != m_rows || a.nonZeros() != m_nonzeros;
    m_rows = a.rows();
    m_nonzeros = a.nonZeros();
    // A singular K (nothing holds the object) may still factor, with pivots at round-off level:
    // that is a failure too.
    m_failed = !m_factor.factor(column_major, new_pattern);
    ++m_factorizations;
    m_factored_rotation = node_rotation;
    m_fixed = fixed;
    m_stale = false;
    m_changed.assign(node_rotation.size(), 0);
    m_covered_blocks = node_rotation.size();
    m_patch.clear();
    m_patch_dirty = false;
    // A CG iteration streams the factor twice (2 flops an entry each way) and multiplies by
    // the matrix once (2 flops a non-zero). The factorisation's flops run in small dense
    // blocks at about half the solve's rate per flop (measured on the liver at level 4: 380
    // Mflop in 57 ms against 5.8 Mflop in 0.45 ms), hence the factor 2.
    m_iteration_flops = 4.0 * static_cast<double>(m_factor.entries()) + 2.0 * static_cast<double>(a.nonZeros());
    m_refactor_cost = 2.0 * m_factor.factor_flops() / m_iteration_flops;
    m_baseline = -1;
    m_excess = 0.0;
}

void RestCholesky::blocks_changed(const std::vector<std::uint32_t>& blocks)
{
    for (std::uint32_t b : blocks)
        if (b < m_changed.size()) m_changed[b] = 1;
    m_patch_dirty = true;
}

void RestCholesky::update(const SystemMatrix* a, const std::vector<unsigned char>& fixed,
                          const std::vector<Eigen::Quaterniond>& node_rotation)
{
    const std::size_t factored = m_factored_rotation.size();
    // Grown without blocks_changed(): nothing says what changed, so factor anew.
    const bool unexplained = node_rotation.size() > m_covered_blocks && !m_patch_dirty;
    if (m_stale || !same_holds(fixed) || node_rotation.size() < factored || unexplained) {
        if (!a) throw std::logic_error("RestCholesky::update: a new factor needs the assembled matrix");
        refactor(*a, fixed, node_rotation);
    } else if (m_patch_dirty) { // grown or changed since the factorisation: patch it
        if (!a) throw std::logic_error("RestCholesky::update: a grown system needs the assembled matrix");
        std::vector<std::uint32_t> seeds;
        for (std::uint32_t b = 0; b < node_rotation.size(); ++b)
            if (b >= factored || m_changed[b]) seeds.push_back(b);
        m_patch_dirty = false;
        m_covered_blocks = node_rotation.size();
        if (!m_patch.build(*a, seeds, a->rows() / 8)) refactor(*a, fixed, node_rotation); // failed, or past an eighth of the system
    }
    // World-frame rotation of each factored block since the factorisation: F Q_now Q_factored^-1 F^T.
    const std::size_t blocks = m_factored_rotation.size();
    m_warp.resize(blocks);
    for (std::size_t n = 0; n < blocks; ++n)
        m_warp[n] = m_frame * (node_rotation[n] * m_factored_rotation[n].conjugate()).toRotationMatrix() * m_frame.transpose();
    // The jumps the factor holds (newer ones live in the patch only).
    m_jump_warp.clear();
    for (const JumpBlock& jump : m_jumps)
        if (jump.block < blocks && jump.node < blocks) m_jump_warp.push_back({jump, jump.sign * (m_warp[jump.block] - m_warp[jump.node])});
}

void RestCholesky::report_iterations(int iterations)
{
    if (m_baseline < 0 || iterations < m_baseline) m_baseline = iterations;
    // A patch solve streams its double-precision factor twice per iteration: 8 flop-equivalents
    // an entry against the float factor's 4.
    const double patch = 8.0 * static_cast<double>(m_patch.entries()) / m_iteration_flops;
    m_excess += iterations * (1.0 + patch) - m_baseline;
    m_stale = m_stale || iterations > m_refactor_iterations || m_excess >= m_refactor_cost;
}

void RestCholesky::apply(const Eigen::VectorXd& r, Eigen::VectorXd& z) const
{
    // z = W A_0^-1 W^T r, W the warp with its jump couplings, on the factored dofs; plus the patch.
    m_scratch.resize(m_rows);
    for (std::size_t n = 0; n < m_warp.size(); ++n) {
        const auto i = static_cast<Eigen::Index>(3 * n);
        m_scratch.segment<3>(i) = m_warp[n].transpose() * r.segment<3>(i);
    }
    for (const auto& [jump, j] : m_jump_warp)
        m_scratch.segment<3>(3 * static_cast<Eigen::Index>(jump.node)) += j.transpose() * r.segment<3>(3 * static_cast<Eigen::Index>(jump.block));
    for (Eigen::Index i = 0; i < m_rows; ++i)
        if (m_fixed[static_cast<std::size_t>(i)]) m_scratch[i] = 0.0;
    m_factor.solve(m_scratch);
    z.setZero(r.size());
    for (std::size_t n = 0; n < m_warp.size(); ++n) {
        const auto i = static_cast<Eigen::Index>(3 * n);
        z.segment<3>(i) = m_warp[n] * m_scratch.segment<3>(i);
    }
    for (const auto& [jump, j] : m_jump_warp)
        z.segment<3>(3 * static_cast<Eigen::Index>(jump.block)) += j * m_scratch.segment<3>(3 * static_cast<Eigen::Index>(jump.node));
    if (!m_patch.empty()) m_patch.add_to(r, z);
    for (std::size_t i = 0; i < m_fixed.size(); ++i)
        if (m_fixed[i]) z[static_cast<Eigen::Index>(i)] = 0.0;
}

} // namespace vox::fem
