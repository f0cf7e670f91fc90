#pragma once
// A geometric multigrid preconditioner from the branched grid's own levels: the coarse spaces are
// the nodes of the next coarser levels, each fine node interpolated trilinearly in the coarse
// element that holds its element's material (so branched, superimposed elements keep their pieces
// apart), coarse matrices by the Galerkin product P^T A P, l1-Jacobi smoothing and a direct
// solve on the coarsest level. One symmetric V-cycle is the preconditioner of the CG solve.

#include "fem/hex_model.hpp"
#include "fem/preconditioner.hpp"

#include <Eigen/Sparse>
#include <Eigen/SparseCholesky>

#include <memory>
#include <vector>

namespace vox::fem {

class Multigrid final : public Preconditioner {
public:
    using Matrix = SystemMatrix;

    /// Prolongations from `model`'s level up to `coarsest_level` (at most grid.max_level()),
    /// stopping early once a level has at most `direct_dofs` degrees of freedom.
    Multigrid(const grid::BranchedGrid& grid, const HexModel& model, int coarsest_level, std::size_t direct_dofs = 3000);

    [[nodiscard]] std::size_t level_count() const { return m_prolongation.size() + 1; }

    /// Rebuilds the coarse matrices for the fine matrix `a` (held dofs: identity rows and columns,
    /// flagged in `fixed`) by Galerkin products. Call after every assembly (never null).
    void update(const Matrix* a, const std::vector<unsigned char>& fixed,
                const std::vector<Eigen::Quaterniond>& node_rotation) override;

    /// z = (one V-cycle) r.
    void apply(const Eigen::VectorXd& r, Eigen::VectorXd& z) const override;
    [[nodiscard]] const char* name() const override { return "multigrid"; }

private:
    void cycle(std::size_t level, const Eigen::VectorXd& r, Eigen::VectorXd& z) const;

    std::vector<Eigen::SparseMatrix<double, Eigen::RowMajor>> m_prolongation; ///< [k]: level k+1 -> k
    std::vector<Matrix> m_matrix;                                             ///< [0] is the fine matrix
    std::vector<Eigen::VectorXd> m_inverse_diagonal; ///< l1-Jacobi: inverse absolute row sums
    Eigen::SimplicialLDLT<Eigen::SparseMatrix<double>> m_coarsest;
};

} // namespace vox::fem
