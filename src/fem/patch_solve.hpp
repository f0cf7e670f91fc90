#pragma once
// An exact solve on a patch of a sparse system: the given dof blocks and every block they couple
// to (one ring of overlap), factored as its own small sparse system. Added to a global
// preconditioner that no longer fits those blocks (P = P_global + R^T A_patch^-1 R, additive
// Schwarz), it repairs the part of the system that changed since the global one was built, at
// the cost of a factorisation of the patch only.

#include <Eigen/SparseCholesky>
#include <Eigen/SparseCore>

#include <cstdint>
#include <vector>

namespace vox::fem {

class PatchSolve {
public:
    /// Builds the patch of `blocks` (3 dofs each) in the row-major symmetric matrix `a` and
    /// factors it. False (and empty) when the patch would hold more than `max_dofs` dofs or is not
    /// positive definite.
    bool build(const Eigen::SparseMatrix<double, Eigen::RowMajor>& a, const std::vector<std::uint32_t>& blocks, Eigen::Index max_dofs);
    void clear() { m_dofs.clear(); }
    [[nodiscard]] bool empty() const { return m_dofs.empty(); }
    [[nodiscard]] std::size_t dofs() const { return m_dofs.size(); }
    /// Non-zeros of the patch's factor (what an application streams twice).
    [[nodiscard]] std::size_t entries() const { return m_dofs.empty() ? 0 : static_cast<std::size_t>(m_factor.matrixL().nestedExpression().nonZeros()); }
    /// z += R^T A_patch^-1 R r.
    void add_to(const Eigen::VectorXd& r, Eigen::VectorXd& z) const;

private:
    std::vector<int> m_dofs; ///< global dof of each patch dof
    Eigen::SimplicialLLT<Eigen::SparseMatrix<double>> m_factor;
    mutable Eigen::VectorXd m_local, m_solution;
};

} // namespace vox::fem
