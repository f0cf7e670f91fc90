#pragma once
// A sparse Cholesky factor for preconditioning: CHOLMOD's supernodal factorisation (dense blocks
// through BLAS, fill-reducing ordering), kept and applied in single precision. As a
// preconditioner the factor need not be exact, and a float copy halves the memory each
// application streams through (on the liver at level 4, 1.1 M non-zeros: about 0.4 ms an
// application instead of 2 ms for a simplicial double factor).
//
// The triangular solves run on all threads: the supernodal elimination tree is cut into disjoint
// subtrees, one group per thread, below a serial top (the separators near the root). Going up, a
// subtree's updates to the top's rows are summed per thread and added before the top is solved;
// going down, the top is solved first and the subtrees only read from it. (On the Is-XFEM bench's
// factor, 2.1 M entries, this is what most of a CG iteration cost: numbers in the README.)

#include "fem/factor_failure.hpp"

#include <Eigen/SparseCore>

#include <functional>
#include <memory>
#include <span>
#include <vector>

namespace vox::fem {

class SupernodalFactor {
public:
    SupernodalFactor();
    ~SupernodalFactor();
    SupernodalFactor(const SupernodalFactor&) = delete;
    SupernodalFactor& operator=(const SupernodalFactor&) = delete;

    /// Factors the symmetric matrix `a` (its lower triangle is read), analysing its pattern first
    /// when `new_pattern`. False when it is not numerically positive definite (a pivot below
    /// 1e-10 of the largest: a singular system, an object nothing holds). The solves are scheduled
    /// for `solve_threads` threads: a factor taken on one thread for solves on another passes the
    /// other's solve_threads(). Runs on the calling thread alone (no TBB algorithms; CHOLMOD and
    /// BLAS are not to be called from two threads at once).
    bool factor(const Eigen::SparseMatrix<double>& a, bool new_pattern, std::size_t solve_threads = SupernodalFactor::solve_threads());
    /// Why the last factor() returned false (failed is false after a success).
    [[nodiscard]] const FactorFailure& failure() const { return m_failure; }
    /// Threads the calling thread's solves may use: its task arena's, within TBB's global limit.
    [[nodiscard]] static std::size_t solve_threads();
    /// x = A^-1 x, in single precision.
    void solve(Eigen::VectorXd& x) const;
    /// The same, calling `between` on y = L^-1 P x (the factor's order) between the forward and
    /// the backward solve: a low-rank correction of the factored matrix acts there
    /// (fem/factor_correction.hpp).
    void solve(Eigen::VectorXd& x, const std::function<void(std::span<float>)>& between) const;
    /// Rows (and columns) of the factored matrix.
    [[nodiscard]] Eigen::Index size() const { return static_cast<Eigen::Index>(m_perm.size()); }
    /// The columns L^-1 P e_d for the dofs `dofs` (single precision). Each is non-zero only on the
    /// rows of the supernodes from the dof's own up to the root of the supernodal tree: `rows`
    /// gets the union of those rows (factor order, ascending), `columns` one column per dof over
    /// them. Solved together, from the leaves up. Returns the flops it took.
    double forward_columns(std::span<const int> dofs, std::vector<int>& rows, Eigen::MatrixXf& columns) const;
    /// What forward_columns() would cost for these dofs, in flops.
    [[nodiscard]] double forward_columns_flops(std::span<const int> dofs) const;
    /// The factor's row (its order) of a dof of the matrix.
    [[nodiscard]] int row_of(int dof) const { return m_inverse_perm[static_cast<std::size_t>(dof)]; }
    /// Entries of the factor (its supernodes' dense blocks).
    [[nodiscard]] std::size_t entries() const { return m_values.size(); }
    /// Floating-point operations of one numerical factorisation (CHOLMOD's count from the analysis).
    [[nodiscard]] double factor_flops() const { return m_factor_flops; }
    /// Groups of subtrees the solves run in parallel (1: serial), and the top's share of the entries.
    [[nodiscard]] std::size_t parallel_groups() const { return m_groups.size(); }
    [[nodiscard]] double top_share() const { return m_top_share; }

private:
    struct Cholmod;
    /// Splits the supernodal tree into up to `groups` parallel groups of subtrees and a serial top.
    void schedule(std::size_t groups);
    void forward(int k, float* b, float* tmp, float* top_delta) const;
    void backward(int k, float* b, float* tmp) const;
    void forward_all(float* b) const;
    /// Per supernode: on the path from one of `dofs`' supernodes to the root.
    [[nodiscard]] std::vector<unsigned char> on_paths(std::span<const int> dofs) const;
    void backward_all(float* b) const;

    std::unique_ptr<Cholmod> m_cholmod;
    std::vector<float> m_values;                      ///< supernodes' blocks, column-major
    std::vector<int> m_super, m_pi, m_px, m_s, m_perm; ///< CHOLMOD's supernodal layout
    std::vector<int> m_inverse_perm;                    ///< dof -> factor row
    std::vector<int> m_column_super, m_parent;         ///< factor row -> its supernode; supernode -> parent (-1: a root)
    FactorFailure m_failure;
    bool m_postordered = false;                        ///< a child's number below its parent's (CHOLMOD's)
    double m_factor_flops = 0.0;
    std::vector<std::vector<int>> m_groups; ///< per group, its supernodes in ascending order
    std::vector<int> m_top;                 ///< supernodes solved serially, ascending
    std::vector<int> m_top_rows;            ///< the top's rows (factor order), and each row's place in them:
    std::vector<int> m_top_place;           ///< -1 below the top
    double m_top_share = 1.0;
    bool m_schedule_stale = true; ///< an analysis whose tree the solves are not planned for yet
    mutable std::vector<float> m_b;
    mutable std::vector<std::vector<float>> m_tmp, m_delta; ///< per group: scratch, updates to the top's rows
};

} // namespace vox::fem
