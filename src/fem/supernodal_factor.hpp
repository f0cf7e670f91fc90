#pragma once
// A sparse Cholesky factor for preconditioning: CHOLMOD's supernodal factorisation (dense blocks
// through BLAS, fill-reducing ordering), kept and applied in single precision. As a
// preconditioner the factor need not be exact, and a float copy halves the memory each
// application streams through (on the liver at level 4, 1.1 M non-zeros: about 0.4 ms an
// application instead of 2 ms for a simplicial double factor).

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
    /// 1e-10 of the largest: a singular system, an object nothing holds).
    bool factor(const Eigen::SparseMatrix<double>& a, bool new_pattern);
    /// x = A^-1 x, in single precision.
    void solve(Eigen::VectorXd& x) const;
    /// Entries of the factor (its supernodes' dense blocks).
    [[nodiscard]] std::size_t entries() const { return m_values.size(); }
    /// Floating-point operations of one numerical factorisation (CHOLMOD's count from the analysis).
    [[nodiscard]] double factor_flops() const { return m_factor_flops; }

private:
    struct Cholmod;
    std::unique_ptr<Cholmod> m_cholmod;
    std::vector<float> m_values;                      ///< supernodes' blocks, column-major
    std::vector<int> m_super, m_pi, m_px, m_s, m_perm; ///< CHOLMOD's supernodal layout
    double m_factor_flops = 0.0;
    mutable std::vector<float> m_b, m_tmp;
};

} // namespace vox::fem
