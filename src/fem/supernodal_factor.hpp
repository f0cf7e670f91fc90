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

#include <Eigen/SparseCore>

#include <memory>
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
    /// Threads the calling thread's solves may use: its task arena's, within TBB's global limit.
    [[nodiscard]] static std::size_t solve_threads();
    /// x = A^-1 x, in single precision.
    void solve(Eigen::VectorXd& x) const;
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

    std::unique_ptr<Cholmod> m_cholmod;
    std::vector<float> m_values;                      ///< supernodes' blocks, column-major
    std::vector<int> m_super, m_pi, m_px, m_s, m_perm; ///< CHOLMOD's supernodal layout
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
