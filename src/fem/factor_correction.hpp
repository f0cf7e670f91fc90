#pragma once
// An exact low-rank correction of a factored matrix for the rows a cut changed (the Woodbury
// identity), so that a factor taken before a cut still preconditions the system after it as well as
// a new factor would.
//
// A cut changes the system matrix only in the rows and columns of the dof set S of the elements it
// touched, and adds dofs (new nodes, enriched blocks). With the factored matrix A0 extended by the
// identity over the new dofs (K), the matrix now is K + E D E^T, E selecting S and D the change of
// the S x S block. Then
//
//     (K + E D E^T)^-1 = K^-1 - K^-1 E C^-1 D E^T K^-1,   C = I + D G,   G = E^T K^-1 E,
//
// which holds for a singular D as well (an element cut away entirely). With K = L L^T (permuted)
// and X = L^-1 E over the old dofs of S, G = X^T X there and the identity over the new dofs, and an
// application costs one solve with the factor and two thin products with X between its forward and
// backward halves: y = L^-1 r; g = (X^T y, r_new); s = C^-1 D g; y -= X s_old, z_new = r_new - s_new;
// z = L^-T y.
//
// X's columns are non-zero only on the rows of the supernodes from their dof's up to the root (on
// the liver at level 4: 870 - 1,600 of 5,500 rows, 35 - 55 % of the factor's entries for one dof),
// so a column costs about half a forward solve. They are computed once per dof, when the dof joins
// S, and kept until the factor is replaced; D and C are rebuilt at every build (S is a few hundred
// dofs at most: C's LU is a few megaflops). C is formed as I + D G rather than from D^-1, which a
// cut that removes an element outright makes singular.
//
// Warped factors (fem/rest_cholesky.hpp): the factor preconditions in each node's rotated frame, so
// D is the change in that frame: W_S^T A_S W_S - A0_S over the S block, W the block rotations.

#include "fem/preconditioner.hpp"
#include "fem/supernodal_factor.hpp"

#include <Eigen/Dense>

#include <span>
#include <vector>

namespace vox::fem {

class FactorCorrection {
public:
    /// Forgets everything (a new factor).
    void clear();
    [[nodiscard]] bool empty() const { return m_old.empty() && m_new.empty(); }
    /// Dofs of S.
    [[nodiscard]] std::size_t dofs() const { return m_old.size() + m_new.size(); }

    /// (Re)builds the correction of `factor` (of the matrix `factored`, row-major, its held dofs
    /// identity rows) for the system `a` (held dofs `fixed`), whose rows of the dof blocks
    /// `blocks` changed since (every block beyond the factored ones included; the old blocks
    /// coupled to new ones are added here). `warp`: per factored block, the rotation from the
    /// factored state to now. Columns of X are kept from earlier builds with the same factor.
    /// False (and empty) when S would exceed `max_dofs`, the build would cost more than
    /// `max_flops` (a cut through many elements at once: a new factor is then the better buy), or
    /// C is singular. `flops` gets what the build cost (new columns of X, G's new entries, C's LU).
    bool build(const SupernodalFactor& factor, const SystemMatrix& factored, const SystemMatrix& a, std::span<const std::uint32_t> blocks,
               const std::vector<Eigen::Matrix3d>& warp, const std::vector<unsigned char>& fixed, std::size_t max_dofs, double max_flops,
               double& flops);

    /// Between the factor's forward and backward solves (SupernodalFactor::solve): corrects the
    /// forward result `y` of the factored dofs, and writes z over the new dofs of S from the
    /// residual `r` (the identity of K there).
    void correct(std::span<float> y, const Eigen::VectorXd& r, Eigen::VectorXd& z_new) const;
    /// Writes the new dofs' part of the last correct() into z.
    void add_new(const Eigen::VectorXd& z_new, Eigen::VectorXd& z) const;
    /// Flops of one application beyond the factor's solve.
    [[nodiscard]] double apply_flops() const;

private:
    const SupernodalFactor* m_factor = nullptr;
    std::vector<int> m_old, m_new;     ///< S: factored dofs (X's columns, in the order they joined), new dofs
    std::vector<int> m_rows;           ///< factor rows X covers, in the order they joined
    std::vector<int> m_row_place;      ///< factor row -> its place in m_rows (-1: none)
    std::vector<int> m_place;          ///< dof -> its place in S (old first, then new), -1: not in S
    Eigen::MatrixXf m_x;               ///< m_rows x m_old
    Eigen::MatrixXd m_g;               ///< X^T X, m_old x m_old
    Eigen::MatrixXd m_d;               ///< the change over S, |S| x |S|
    Eigen::PartialPivLU<Eigen::MatrixXd> m_c;
    mutable Eigen::VectorXd m_g_vector, m_s;
    mutable Eigen::VectorXf m_gathered;
};

} // namespace vox::fem
