#include "fem/patch_solve.hpp"

#include <algorithm>

namespace vox::fem {

bool PatchSolve::build(const Eigen::SparseMatrix<double, Eigen::RowMajor>& a, const std::vector<std::uint32_t>& blocks, Eigen::Index max_dofs)
{
    const auto block_count = static_cast<std::size_t>(a.rows() / 3);
    std::vector<unsigned char> in(block_count, 0);
    std::vector<std::uint32_t> patch;
    auto take = [&](std::uint32_t b) {
        if (!in[b]) {
            in[b] = 1;
            patch.push_back(b);
        }
    };
    for (std::uint32_t b : blocks) take(b);
    const std::size_t seeds = patch.size();
    for (std::size_t s = 0; s < seeds; ++s) // one ring: every block a seed's rows reach
        for (int i = 0; i < 3; ++i)
            for (Eigen::SparseMatrix<double, Eigen::RowMajor>::InnerIterator it(a, 3 * static_cast<Eigen::Index>(patch[s]) + i); it; ++it)
                take(static_cast<std::uint32_t>(it.col() / 3));
    if (static_cast<Eigen::Index>(3 * patch.size()) > max_dofs) {
        m_dofs.clear();
        return false;
    }
    std::sort(patch.begin(), patch.end());
    std::vector<int> local(static_cast<std::size_t>(a.rows()), -1);
    m_dofs.clear();
    for (std::uint32_t b : patch)
        for (int i = 0; i < 3; ++i) {
            local[3 * b + static_cast<std::uint32_t>(i)] = static_cast<int>(m_dofs.size());
            m_dofs.push_back(3 * static_cast<int>(b) + i);
        }
    std::vector<Eigen::Triplet<double>> entries;
    for (std::size_t row = 0; row < m_dofs.size(); ++row)
        for (Eigen::SparseMatrix<double, Eigen::RowMajor>::InnerIterator it(a, m_dofs[row]); it; ++it)
            if (const int column = local[static_cast<std::size_t>(it.col())]; column >= 0)
                entries.emplace_back(static_cast<int>(row), column, it.value());
    Eigen::SparseMatrix<double> patch_matrix(static_cast<Eigen::Index>(m_dofs.size()), static_cast<Eigen::Index>(m_dofs.size()));
    patch_matrix.setFromTriplets(entries.begin(), entries.end());
    m_factor.compute(patch_matrix);
    if (m_factor.info() != Eigen::Success) {
        m_dofs.clear();
        return false;
    }
    return true;
}

void PatchSolve::add_to(const Eigen::VectorXd& r, Eigen::VectorXd& z) const
{
    m_local.resize(static_cast<Eigen::Index>(m_dofs.size()));
    for (std::size_t i = 0; i < m_dofs.size(); ++i) m_local[static_cast<Eigen::Index>(i)] = r[m_dofs[i]];
    m_solution = m_factor.solve(m_local);
    for (std::size_t i = 0; i < m_dofs.size(); ++i) z[m_dofs[i]] += m_solution[static_cast<Eigen::Index>(i)];
}

} // namespace vox::fem
