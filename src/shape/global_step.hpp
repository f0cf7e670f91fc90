#pragma once
// The global step of shape matching as projective dynamics solves it (Bouaziz, Martin, Liu,
// Kavan and Pauly 2014, whose shape-matching constraints are these clusters): with every
// cluster's rotation R fixed, Phi is quadratic in the positions,
//   Phi = sum_j m_j / (2 dt^2) |p_j - y_j|^2 + sum_c 1/2 sum_j w_j |(p_j - c(p)) - R q_j|^2,
// c(p) the cluster's weighted centroid, and its minimiser solves one linear system per axis,
//   (M / dt^2 + sum_c (W_c - w_c w_c^T / sum w_c)) p = M y / dt^2 + sum_c W_c R q,
// whose matrix does not depend on the rotations: it is factored once and each iteration costs a
// back-substitution. Where the paper's averaging (one particle at a time) needs thousands of
// iterations to carry a load along a stiff beam, this carries it in one. Held dofs are identity
// rows; a matrix is kept per axis only when the axes hold different dofs.

#include "shape/cluster_hierarchy.hpp"

#include <Eigen/Sparse>
#include <Eigen/SparseCholesky>

#include <array>
#include <memory>
#include <vector>

namespace vox::shape {

class GlobalStep {
public:
    /// Factors the system for `level`'s clusters (stiffness times `scale` per cluster), the
    /// particles' `inertia` (m / dt^2; 0 statically, where a small floor keeps free pieces
    /// solvable) and the held dofs `fixed` (per dof), unless they are those of the last factorisation.
    void prepare(const ClusterLevel& level, const std::vector<double>& scale, const std::vector<double>& inertia,
                 const std::vector<unsigned char>& fixed);
    /// out = A^-1 rhs on the free dofs, zero on the held ones (the step solves for corrections,
    /// which held dofs do not take).
    void solve(const std::vector<Eigen::Vector3d>& rhs, std::vector<Eigen::Vector3d>& out) const;
    /// out = A u, every dof (the matrix without holds).
    void multiply_full(const std::vector<Eigen::Vector3d>& u, std::vector<Eigen::Vector3d>& out) const;
    /// out = A u on the free dofs (held dofs: 0), u zero on held dofs.
    void multiply(const std::vector<Eigen::Vector3d>& u, std::vector<Eigen::Vector3d>& out) const;
    [[nodiscard]] int factorizations() const { return m_factorizations; }

private:
    using Matrix = Eigen::SparseMatrix<double>;
    Matrix m_full;                        ///< without holds, one axis
    std::array<std::shared_ptr<Eigen::SimplicialLDLT<Matrix>>, 3> m_factor; ///< per axis (shared when the holds agree)
    std::array<std::vector<unsigned char>, 3> m_held; ///< per axis, per particle
    std::vector<double> m_scale, m_inertia;
    std::vector<unsigned char> m_fixed;
    int m_factorizations = 0;
};

} // namespace vox::shape
