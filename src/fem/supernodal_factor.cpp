#include "fem/supernodal_factor.hpp"

#include <Eigen/Core>

#include <cholmod.h>

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace vox::fem {

struct SupernodalFactor::Cholmod {
    cholmod_common common{};
    cholmod_factor* factor = nullptr;
    Cholmod()
    {
        cholmod_start(&common);
        common.supernodal = CHOLMOD_SUPERNODAL;
        common.final_ll = 1;
        common.print = 0;
    }
    ~Cholmod()
    {
        if (factor) cholmod_free_factor(&factor, &common);
        cholmod_finish(&common);
    }
};

SupernodalFactor::SupernodalFactor() : m_cholmod(std::make_unique<Cholmod>()) {}
SupernodalFactor::~SupernodalFactor() = default;

bool SupernodalFactor::factor(const Eigen::SparseMatrix<double>& a, bool new_pattern)
{
    cholmod_sparse view{};
    view.nrow = view.ncol = static_cast<std::size_t>(a.rows());
    view.nzmax = static_cast<std::size_t>(a.nonZeros());
    view.p = const_cast<int*>(a.outerIndexPtr());
    view.i = const_cast<int*>(a.innerIndexPtr());
    view.x = const_cast<double*>(a.valuePtr());
    view.stype = -1; // symmetric, lower triangle stored (what is read)
    view.itype = CHOLMOD_INT;
    view.xtype = CHOLMOD_REAL;
    view.dtype = CHOLMOD_DOUBLE;
    view.sorted = 1;
    view.packed = a.isCompressed() ? 1 : 0;
    if (!view.packed) throw std::logic_error("SupernodalFactor: the matrix must be compressed");
    cholmod_common& c = m_cholmod->common;
    if (new_pattern || !m_cholmod->factor) {
        if (m_cholmod->factor) cholmod_free_factor(&m_cholmod->factor, &c);
        m_cholmod->factor = cholmod_analyze(&view, &c);
        if (!m_cholmod->factor) throw std::runtime_error("SupernodalFactor: CHOLMOD could not analyse the matrix");
        m_factor_flops = c.fl;
    }
    cholmod_factorize(&view, m_cholmod->factor, &c);
    const cholmod_factor* l = m_cholmod->factor;
    if (c.status == CHOLMOD_NOT_POSDEF || !l->is_super || !l->is_ll) return false;
    // The float copy, and the pivots (the squared diagonal of L) for the singularity check.
    auto copy = [](const void* p, std::size_t n, std::vector<int>& out) {
        const int* q = static_cast<const int*>(p);
        out.assign(q, q + n);
    };
    copy(l->super, l->nsuper + 1, m_super);
    copy(l->pi, l->nsuper + 1, m_pi);
    copy(l->px, l->nsuper + 1, m_px);
    copy(l->s, l->ssize, m_s);
    copy(l->Perm, l->n, m_perm);
    const double* x = static_cast<const double*>(l->x);
    m_values.assign(x, x + l->xsize);
    double smallest = INFINITY, largest = 0.0;
    for (std::size_t k = 0; k + 1 < m_super.size(); ++k) {
        const int nc = m_super[k + 1] - m_super[k], nr = m_pi[k + 1] - m_pi[k];
        for (int j = 0; j < nc; ++j) {
            const double d = x[m_px[k] + j * nr + j];
            smallest = std::min(smallest, d * d);
            largest = std::max(largest, d * d);
        }
    }
    m_b.resize(l->n);
    m_tmp.resize(l->n);
    return smallest > 1e-10 * largest;
}

void SupernodalFactor::solve(Eigen::VectorXd& v) const
{
    const int n = static_cast<int>(m_perm.size());
    for (int i = 0; i < n; ++i) m_b[static_cast<std::size_t>(i)] = static_cast<float>(v[m_perm[static_cast<std::size_t>(i)]]);
    const int supernodes = static_cast<int>(m_super.size()) - 1;
    // L y = P b, supernode by supernode: the diagonal block's triangle, then the rows below.
    for (int k = 0; k < supernodes; ++k) {
        const int c0 = m_super[k], nc = m_super[k + 1] - c0, nr = m_pi[k + 1] - m_pi[k], below = nr - nc;
        const Eigen::Map<const Eigen::MatrixXf> block(m_values.data() + m_px[k], nr, nc);
        Eigen::Map<Eigen::VectorXf> y(m_b.data() + c0, nc);
        block.topRows(nc).triangularView<Eigen::Lower>().solveInPlace(y);
        if (below == 0) continue;
        Eigen::Map<Eigen::VectorXf> t(m_tmp.data(), below);
        t.noalias() = block.bottomRows(below) * y;
        const int* rows = m_s.data() + m_pi[k] + nc;
        for (int i = 0; i < below; ++i) m_b[static_cast<std::size_t>(rows[i])] -= t[i];
    }
    // L^T x = y, backwards.
    for (int k = supernodes - 1; k >= 0; --k) {
        const int c0 = m_super[k], nc = m_super[k + 1] - c0, nr = m_pi[k + 1] - m_pi[k], below = nr - nc;
        const Eigen::Map<const Eigen::MatrixXf> block(m_values.data() + m_px[k], nr, nc);
        Eigen::Map<Eigen::VectorXf> x(m_b.data() + c0, nc);
        if (below > 0) {
            Eigen::Map<Eigen::VectorXf> t(m_tmp.data(), below);
            const int* rows = m_s.data() + m_pi[k] + nc;
            for (int i = 0; i < below; ++i) t[i] = m_b[static_cast<std::size_t>(rows[i])];
            x.noalias() -= block.bottomRows(below).transpose() * t;
        }
        block.topRows(nc).transpose().triangularView<Eigen::Upper>().solveInPlace(x);
    }
    for (int i = 0; i < n; ++i) v[m_perm[static_cast<std::size_t>(i)]] = m_b[static_cast<std::size_t>(i)];
}

} // namespace vox::fem
