#include "fem/supernodal_factor.hpp"

#include <Eigen/Core>
#include <Eigen/Dense>

#include <cholmod.h>
#include <tbb/global_control.h>
#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>

#include <algorithm>
#include <cmath>
#include <functional>
#include <mutex>
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

std::size_t SupernodalFactor::solve_threads()
{
    return static_cast<std::size_t>(std::min<long>(tbb::this_task_arena::max_concurrency(),
                                                   static_cast<long>(tbb::global_control::active_value(tbb::global_control::max_allowed_parallelism))));
}

bool SupernodalFactor::factor(const Eigen::SparseMatrix<double>& a, bool new_pattern, std::size_t solve_threads)
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
    // Serial OpenBLAS (0.3.7 on) is safe to call from two threads at once only when built with
    // USE_LOCKING, and factors may be taken in the background, by several solvers each: one
    // factorisation at a time in the process.
    static std::mutex blas;
    std::unique_lock lock(blas);
    const bool analyse = new_pattern || !m_cholmod->factor;
    if (analyse) {
        m_schedule_stale = true; // planned below, once a factor of this analysis holds
        if (m_cholmod->factor) cholmod_free_factor(&m_cholmod->factor, &c);
        m_cholmod->factor = cholmod_analyze(&view, &c);
        if (!m_cholmod->factor) throw std::runtime_error("SupernodalFactor: CHOLMOD could not analyse the matrix");
        m_factor_flops = c.fl;
    }
    cholmod_factorize(&view, m_cholmod->factor, &c);
    const cholmod_factor* l = m_cholmod->factor;
    lock.unlock();
    m_failure = {};
    if (c.status == CHOLMOD_NOT_POSDEF || !l->is_super || !l->is_ll) {
        // CHOLMOD stops at the column (factor order) whose pivot was not positive: its `minor`.
        const auto* perm = static_cast<const int*>(l->Perm);
        const int dof = l->minor < l->n && perm ? perm[l->minor] : -1;
        // A singular matrix (a piece nothing holds, no mass) fails as often by a pivot rounded to
        // zero or below as by a tiny one. Shifted by 1e-8 of its largest diagonal entry a positive
        // semi-definite matrix factors; an indefinite one does not.
        double beta[2] = {1e-8 * a.diagonal().cwiseAbs().maxCoeff(), 0.0};
        lock.lock();
        cholmod_factorize_p(&view, beta, nullptr, 0, m_cholmod->factor, &c);
        const bool semidefinite = c.status == CHOLMOD_OK && m_cholmod->factor->is_super;
        lock.unlock();
        m_failure = {true, !semidefinite, dof, 0.0};
        return false;
    }
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
    m_inverse_perm.resize(m_perm.size());
    for (std::size_t i = 0; i < m_perm.size(); ++i) m_inverse_perm[static_cast<std::size_t>(m_perm[i])] = static_cast<int>(i);
    const double* x = static_cast<const double*>(l->x);
    m_values.assign(x, x + l->xsize);
    double smallest = INFINITY, largest = 0.0;
    int smallest_row = -1;
    for (std::size_t k = 0; k + 1 < m_super.size(); ++k) {
        const int nc = m_super[k + 1] - m_super[k], nr = m_pi[k + 1] - m_pi[k];
        for (int j = 0; j < nc; ++j) {
            const double d = x[m_px[k] + j * nr + j];
            if (d * d < smallest) smallest_row = m_super[k] + j;
            smallest = std::min(smallest, d * d);
            largest = std::max(largest, d * d);
        }
    }
    m_b.resize(l->n);
    if (m_schedule_stale) { // the tree is the analysis's (a failed first factor of it leaves this to the next)
        schedule(std::min<std::size_t>(solve_threads, 8));
        m_schedule_stale = false;
    }
    if (smallest > 1e-10 * largest) return true;
    m_failure = {true, false, smallest_row >= 0 ? m_perm[static_cast<std::size_t>(smallest_row)] : -1, smallest / largest};
    return false;
}

void SupernodalFactor::schedule(std::size_t groups)
{
    const int supernodes = static_cast<int>(m_super.size()) - 1;
    std::vector<int>& column_super = m_column_super;
    column_super.assign(static_cast<std::size_t>(m_super.back()), 0);
    for (int k = 0; k < supernodes; ++k)
        for (int c = m_super[k]; c < m_super[k + 1]; ++c) column_super[static_cast<std::size_t>(c)] = k;
    // The supernodal tree: a supernode's parent holds its first row below the diagonal block.
    // Work is counted in factor entries (what a solve streams).
    std::vector<std::vector<int>> children(static_cast<std::size_t>(supernodes));
    std::vector<double> work(static_cast<std::size_t>(supernodes)), subtree(static_cast<std::size_t>(supernodes), 0.0);
    std::vector<int>& parent = m_parent;
    parent.assign(static_cast<std::size_t>(supernodes), -1);
    std::vector<int> frontier; // the roots, then the subtrees left below the top
    bool postordered = true;
    for (int k = 0; k < supernodes; ++k) {
        const int nc = m_super[k + 1] - m_super[k], nr = m_pi[k + 1] - m_pi[k];
        work[static_cast<std::size_t>(k)] = static_cast<double>(nr) * nc;
        if (nr == nc) {
            frontier.push_back(k);
            continue;
        }
        const int p = parent[static_cast<std::size_t>(k)] = column_super[static_cast<std::size_t>(m_s[static_cast<std::size_t>(m_pi[k] + nc)])];
        postordered = postordered && p > k;
        children[static_cast<std::size_t>(p)].push_back(k);
    }
    m_postordered = postordered;
    for (int k = 0; k < supernodes && postordered; ++k) {
        subtree[static_cast<std::size_t>(k)] += work[static_cast<std::size_t>(k)];
        if (parent[static_cast<std::size_t>(k)] >= 0) subtree[static_cast<std::size_t>(parent[static_cast<std::size_t>(k)])] += subtree[static_cast<std::size_t>(k)];
    }
    // Split the heaviest subtree (its root joins the serial top) while that shortens the
    // estimated solve, top plus the heaviest group (subtrees dealt largest first to the lightest
    // group); keep the best split seen.
    auto by_weight = [&](int a, int b) { return subtree[static_cast<std::size_t>(a)] > subtree[static_cast<std::size_t>(b)]; };
    auto deal = [&](const std::vector<int>& trees) {
        std::vector<std::vector<int>> dealt(groups);
        std::vector<double> load(groups, 0.0);
        for (int t : trees) {
            const auto g = static_cast<std::size_t>(std::min_element(load.begin(), load.end()) - load.begin());
            dealt[g].push_back(t);
            load[g] += subtree[static_cast<std::size_t>(t)];
        }
        return std::pair{dealt, *std::max_element(load.begin(), load.end())};
    };
    double total = 0.0;
    for (double w : work) total += w;
    double top_work = 0.0, best = total, best_top = total;
    std::vector<int> best_frontier;
    for (int split = 0; postordered && groups > 1 && split < 256 && !frontier.empty(); ++split) {
        std::sort(frontier.begin(), frontier.end(), by_weight);
        const double cost = top_work + deal(frontier).second;
        if (cost < 0.98 * best) {
            best = cost;
            best_top = top_work;
            best_frontier = frontier;
        }
        const int heaviest = frontier.front();
        if (children[static_cast<std::size_t>(heaviest)].empty()) break;
        top_work += work[static_cast<std::size_t>(heaviest)];
        frontier.erase(frontier.begin());
        frontier.insert(frontier.end(), children[static_cast<std::size_t>(heaviest)].begin(), children[static_cast<std::size_t>(heaviest)].end());
    }
    // Groups of whole subtrees; everything else is the top.
    m_groups.clear();
    std::vector<unsigned char> grouped(static_cast<std::size_t>(supernodes), 0);
    for (std::vector<int>& trees : deal(best_frontier).first) {
        std::vector<int> nodes;
        std::function<void(int)> collect = [&](int k) {
            nodes.push_back(k);
            grouped[static_cast<std::size_t>(k)] = 1;
            for (int c : children[static_cast<std::size_t>(k)]) collect(c);
        };
        for (int t : trees) collect(t);
        if (nodes.empty()) continue;
        std::sort(nodes.begin(), nodes.end());
        m_groups.push_back(std::move(nodes));
    }
    m_top.clear();
    m_top_rows.clear();
    m_top_place.assign(m_super.back() > 0 ? static_cast<std::size_t>(m_super.back()) : 0, -1);
    for (int k = 0; k < supernodes; ++k)
        if (!grouped[static_cast<std::size_t>(k)]) {
            m_top.push_back(k);
            for (int c = m_super[k]; c < m_super[k + 1]; ++c) {
                m_top_place[static_cast<std::size_t>(c)] = static_cast<int>(m_top_rows.size());
                m_top_rows.push_back(c);
            }
        }
    m_top_share = total > 0.0 ? best_top / total : 1.0;
    int widest = 0;
    for (int k = 0; k < supernodes; ++k) widest = std::max(widest, m_pi[k + 1] - m_pi[k]);
    m_tmp.assign(std::max<std::size_t>(m_groups.size(), 1), std::vector<float>(static_cast<std::size_t>(widest)));
    m_delta.assign(m_groups.size(), std::vector<float>(m_top_rows.size()));
}

void SupernodalFactor::forward(int k, float* b, float* tmp, float* top_delta) const
{
    // L y = P b at supernode k: the diagonal block's triangle, then the rows below (into the
    // top's deltas when solving a group in parallel).
    const int c0 = m_super[k], nc = m_super[k + 1] - c0, nr = m_pi[k + 1] - m_pi[k], below = nr - nc;
    const Eigen::Map<const Eigen::MatrixXf> block(m_values.data() + m_px[k], nr, nc);
    Eigen::Map<Eigen::VectorXf> y(b + c0, nc);
    block.topRows(nc).triangularView<Eigen::Lower>().solveInPlace(y);
    if (below == 0) return;
    Eigen::Map<Eigen::VectorXf> t(tmp, below);
    t.noalias() = block.bottomRows(below) * y;
    const int* rows = m_s.data() + m_pi[k] + nc;
    for (int i = 0; i < below; ++i) {
        const int place = top_delta ? m_top_place[static_cast<std::size_t>(rows[i])] : -1;
        if (place >= 0)
            top_delta[place] += t[i];
        else
            b[rows[i]] -= t[i];
    }
}

void SupernodalFactor::backward(int k, float* b, float* tmp) const
{
    // L^T x = y at supernode k: the rows below (solved already) first, then the triangle.
    const int c0 = m_super[k], nc = m_super[k + 1] - c0, nr = m_pi[k + 1] - m_pi[k], below = nr - nc;
    const Eigen::Map<const Eigen::MatrixXf> block(m_values.data() + m_px[k], nr, nc);
    Eigen::Map<Eigen::VectorXf> x(b + c0, nc);
    if (below > 0) {
        Eigen::Map<Eigen::VectorXf> t(tmp, below);
        const int* rows = m_s.data() + m_pi[k] + nc;
        for (int i = 0; i < below; ++i) t[i] = b[rows[i]];
        x.noalias() -= block.bottomRows(below).transpose() * t;
    }
    block.topRows(nc).transpose().triangularView<Eigen::Upper>().solveInPlace(x);
}

void SupernodalFactor::forward_all(float* b) const
{
    // The groups' subtrees in parallel, their updates to the top summed, then the top.
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, m_groups.size(), 1),
                      [&](const tbb::blocked_range<std::size_t>& r) {
                          for (std::size_t g = r.begin(); g != r.end(); ++g) {
                              std::fill(m_delta[g].begin(), m_delta[g].end(), 0.0f);
                              for (int k : m_groups[g]) forward(k, b, m_tmp[g].data(), m_delta[g].data());
                          }
                      },
                      tbb::simple_partitioner());
    for (const std::vector<float>& delta : m_delta)
        for (std::size_t j = 0; j < delta.size(); ++j) b[m_top_rows[j]] -= delta[j];
    for (int k : m_top) forward(k, b, m_tmp.front().data(), nullptr);
}

void SupernodalFactor::backward_all(float* b) const
{
    // The top, then the groups in parallel.
    for (auto k = m_top.rbegin(); k != m_top.rend(); ++k) backward(*k, b, m_tmp.front().data());
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, m_groups.size(), 1),
                      [&](const tbb::blocked_range<std::size_t>& r) {
                          for (std::size_t g = r.begin(); g != r.end(); ++g)
                              for (auto k = m_groups[g].rbegin(); k != m_groups[g].rend(); ++k) backward(*k, b, m_tmp[g].data());
                      },
                      tbb::simple_partitioner());
}

void SupernodalFactor::solve(Eigen::VectorXd& v) const { solve(v, {}); }

void SupernodalFactor::solve(Eigen::VectorXd& v, const std::function<void(std::span<float>)>& between) const
{
    const int n = static_cast<int>(m_perm.size());
    for (int i = 0; i < n; ++i) m_b[static_cast<std::size_t>(i)] = static_cast<float>(v[m_perm[static_cast<std::size_t>(i)]]);
    forward_all(m_b.data());
    if (between) between(std::span<float>(m_b.data(), m_b.size()));
    backward_all(m_b.data());
    for (int i = 0; i < n; ++i) v[m_perm[static_cast<std::size_t>(i)]] = m_b[static_cast<std::size_t>(i)];
}

std::vector<unsigned char> SupernodalFactor::on_paths(std::span<const int> dofs) const
{
    if (!m_postordered) throw std::logic_error("SupernodalFactor::forward_columns: the supernodal tree is not in postorder");
    std::vector<unsigned char> on(m_parent.size(), 0);
    for (const int d : dofs)
        for (int k = m_column_super[static_cast<std::size_t>(row_of(d))]; k >= 0 && !on[static_cast<std::size_t>(k)]; k = m_parent[static_cast<std::size_t>(k)])
            on[static_cast<std::size_t>(k)] = 1;
    return on;
}

double SupernodalFactor::forward_columns_flops(std::span<const int> dofs) const
{
    const std::vector<unsigned char> on = on_paths(dofs);
    double entries = 0.0;
    for (std::size_t k = 0; k < on.size(); ++k)
        if (on[k]) entries += static_cast<double>(m_pi[k + 1] - m_pi[k]) * (m_super[k + 1] - m_super[k]);
    return 2.0 * entries * static_cast<double>(dofs.size());
}

double SupernodalFactor::forward_columns(std::span<const int> dofs, std::vector<int>& rows, Eigen::MatrixXf& columns) const
{
    // The supernodes on the dofs' paths to the root, in ascending order (a child before its
    // parent, CHOLMOD's postorder), and their rows.
    const std::vector<unsigned char> on = on_paths(dofs);
    const auto supernodes = on.size();
    rows.clear();
    std::vector<int> place(m_perm.size(), -1);
    for (std::size_t k = 0; k < supernodes; ++k)
        if (on[k])
            for (int c = m_super[k]; c < m_super[k + 1]; ++c) {
                place[static_cast<std::size_t>(c)] = static_cast<int>(rows.size());
                rows.push_back(c);
            }
    columns.setZero(static_cast<Eigen::Index>(rows.size()), static_cast<Eigen::Index>(dofs.size()));
    for (std::size_t j = 0; j < dofs.size(); ++j) columns(place[static_cast<std::size_t>(row_of(dofs[j]))], static_cast<Eigen::Index>(j)) = 1.0f;
    Eigen::MatrixXf below_update;
    double flops = 0.0;
    for (std::size_t k = 0; k < supernodes; ++k) {
        if (!on[k]) continue;
        const int c0 = m_super[k], nc = m_super[k + 1] - c0, nr = m_pi[k + 1] - m_pi[k], below = nr - nc;
        flops += 2.0 * static_cast<double>(nr) * nc * static_cast<double>(dofs.size());
        const Eigen::Map<const Eigen::MatrixXf> block(m_values.data() + m_px[k], nr, nc);
        auto y = columns.middleRows(place[static_cast<std::size_t>(c0)], nc); // the supernode's rows are consecutive there
        block.topRows(nc).triangularView<Eigen::Lower>().solveInPlace(y);
        if (below == 0) continue;
        below_update.noalias() = block.bottomRows(below) * y;
        const int* below_rows = m_s.data() + m_pi[k] + nc; // all in ancestors: on the path
        for (int i = 0; i < below; ++i) columns.row(place[static_cast<std::size_t>(below_rows[i])]) -= below_update.row(i);
    }
    return flops;
}

} // namespace vox::fem
