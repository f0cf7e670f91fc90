#include "fem/factor_correction.hpp"

#include <algorithm>
#include <cmath>
#include <Eigen/SparseCore>

namespace vox::fem {

void FactorCorrection::clear()
{
    m_factor = nullptr;
    m_old.clear();
    m_new.clear();
    m_rows.clear();
    m_row_place.clear();
    m_place.clear();
    m_x.resize(0, 0);
    m_g.resize(0, 0);
    m_d.resize(0, 0);
}

bool FactorCorrection::build(const SupernodalFactor& factor, const SystemMatrix& factored, const SystemMatrix& a,
                             std::span<const std::uint32_t> blocks, const std::vector<Eigen::Matrix3d>& warp,
                             const std::vector<unsigned char>& fixed, std::size_t max_dofs, double max_flops, double& flops)
{
    flops = 0.0;
    if (m_factor != &factor) {
        clear();
        m_factor = &factor;
        m_row_place.assign(static_cast<std::size_t>(factor.size()), -1);
    }
    const Eigen::Index n = factor.size(), total = a.rows();
    const auto block_count = static_cast<std::size_t>(total / 3), factored_blocks = static_cast<std::size_t>(n / 3);
    // S's blocks: those named, every new one, the old ones coupled to new ones, and those already in S.
    std::vector<unsigned char> in_s(block_count, 0);
    for (const std::uint32_t b : blocks)
        if (b < block_count) in_s[b] = 1;
    for (std::size_t b = factored_blocks; b < block_count; ++b) in_s[b] = 1;
    for (Eigen::Index row = n; row < total; ++row)
        for (SystemMatrix::InnerIterator it(a, row); it; ++it)
            if (it.col() < n) in_s[static_cast<std::size_t>(it.col() / 3)] = 1;
    for (const int d : m_old) in_s[static_cast<std::size_t>(d / 3)] = 1;
    std::vector<unsigned char> known(static_cast<std::size_t>(n), 0);
    for (const int d : m_old) known[static_cast<std::size_t>(d)] = 1;
    std::vector<int> joining;
    m_new.clear();
    for (std::size_t b = 0; b < block_count; ++b)
        for (std::size_t i = 0; in_s[b] && i < 3; ++i) {
            const auto d = static_cast<int>(3 * b + i);
            if (fixed[static_cast<std::size_t>(d)]) continue;
            if (d >= n) m_new.push_back(d);
            else if (!known[static_cast<std::size_t>(d)]) joining.push_back(d);
        }
    const double s_estimate = static_cast<double>(m_old.size() + joining.size() + m_new.size());
    if (s_estimate > static_cast<double>(max_dofs) ||
        (joining.empty() ? 0.0 : factor.forward_columns_flops(joining)) + 2.0 / 3.0 * s_estimate * s_estimate * s_estimate > max_flops) {
        clear();
        return false;
    }
    // X's columns for the dofs joining S; the old columns are zero on rows new to X.
    if (!joining.empty()) {
        std::vector<int> rows;
        Eigen::MatrixXf columns;
        flops += factor.forward_columns(joining, rows, columns);
        const Eigen::Index m = static_cast<Eigen::Index>(m_old.size()), k = static_cast<Eigen::Index>(joining.size());
        const Eigen::Index rows_before = static_cast<Eigen::Index>(m_rows.size());
        for (const int r : rows)
            if (m_row_place[static_cast<std::size_t>(r)] < 0) {
                m_row_place[static_cast<std::size_t>(r)] = static_cast<int>(m_rows.size());
                m_rows.push_back(r);
            }
        const Eigen::Index rows_now = static_cast<Eigen::Index>(m_rows.size());
        m_x.conservativeResize(rows_now, m + k);
        m_x.bottomLeftCorner(rows_now - rows_before, m).setZero();
        m_x.rightCols(k).setZero();
        for (std::size_t i = 0; i < rows.size(); ++i)
            m_x.row(m_row_place[static_cast<std::size_t>(rows[i])]).tail(k) = columns.row(static_cast<Eigen::Index>(i));
        const Eigen::MatrixXf cross = m_x.transpose() * m_x.rightCols(k); // G's new columns
        m_g.conservativeResize(m + k, m + k);
        m_g.rightCols(k) = cross.cast<double>();
        m_g.bottomLeftCorner(k, m) = cross.topRows(m).transpose().cast<double>();
        flops += 2.0 * static_cast<double>(rows_now) * static_cast<double>(m + k) * static_cast<double>(k);
        m_old.insert(m_old.end(), joining.begin(), joining.end());
    }
    const Eigen::Index old = static_cast<Eigen::Index>(m_old.size()), s = old + static_cast<Eigen::Index>(m_new.size());
    m_place.assign(static_cast<std::size_t>(total), -1);
    for (std::size_t j = 0; j < m_old.size(); ++j) m_place[static_cast<std::size_t>(m_old[j])] = static_cast<int>(j);
    for (std::size_t j = 0; j < m_new.size(); ++j) m_place[static_cast<std::size_t>(m_new[j])] = static_cast<int>(old + static_cast<Eigen::Index>(j));
    if (s == 0) return true;

    // D = W^T A W - K over S, block by block (W: the factored blocks' warps, the identity beyond).
    Eigen::MatrixXd d = Eigen::MatrixXd::Zero(s, s);
    const auto turn = [&](std::size_t b) -> Eigen::Matrix3d { return b < warp.size() ? warp[b] : Eigen::Matrix3d::Identity(); };
    std::vector<Eigen::Matrix3d> row_blocks(block_count, Eigen::Matrix3d::Zero());
    std::vector<unsigned char> listed(block_count, 0);
    std::vector<std::size_t> touched;
    for (std::size_t b = 0; b < block_count; ++b) {
        if (!in_s[b]) continue;
        touched.clear();
        for (int i = 0; i < 3; ++i)
            for (SystemMatrix::InnerIterator it(a, static_cast<Eigen::Index>(3 * b) + i); it; ++it) {
                const auto c = static_cast<std::size_t>(it.col() / 3);
                if (!in_s[c]) continue;
                if (!listed[c]) {
                    listed[c] = 1;
                    touched.push_back(c);
                }
                row_blocks[c](i, it.col() % 3) += it.value();
            }
        for (const std::size_t c : touched) {
            const Eigen::Matrix3d turned = turn(b).transpose() * row_blocks[c] * turn(c);
            row_blocks[c].setZero();
            listed[c] = 0;
            for (int i = 0; i < 3; ++i)
                for (int j = 0; j < 3; ++j) {
                    const int p = m_place[3 * b + static_cast<std::size_t>(i)], q = m_place[3 * c + static_cast<std::size_t>(j)];
                    if (p >= 0 && q >= 0) d(p, q) += turned(i, j);
                }
        }
    }
    for (const int dof : m_old)
        for (SystemMatrix::InnerIterator it(factored, dof); it; ++it)
            if (const int q = m_place[static_cast<std::size_t>(it.col())]; q >= 0) d(m_place[static_cast<std::size_t>(dof)], q) -= it.value();
    for (Eigen::Index j = old; j < s; ++j) d(j, j) -= 1.0; // K is the identity over the new dofs

    // C = I + D G, G = diag(X^T X, I). D couples only neighbouring blocks: a sparse product.
    const Eigen::SparseMatrix<double> sparse_d = d.sparseView(0.0, 0.0);
    Eigen::MatrixXd c = Eigen::MatrixXd::Identity(s, s);
    c.leftCols(old).noalias() += sparse_d.leftCols(old) * m_g;
    c.rightCols(s - old) += d.rightCols(s - old);
    const double nonzeros = static_cast<double>(sparse_d.nonZeros());
    m_c.compute(c);
    if (!(m_c.rcond() > 1e-12)) {
        clear();
        return false;
    }
    m_d = std::move(d);
    flops += 2.0 * nonzeros * static_cast<double>(old) + 2.0 / 3.0 * std::pow(static_cast<double>(s), 3);
    return true;
}

void FactorCorrection::correct(std::span<float> y, const Eigen::VectorXd& r, Eigen::VectorXd& z_new) const
{
    const Eigen::Index old = static_cast<Eigen::Index>(m_old.size()), s = old + static_cast<Eigen::Index>(m_new.size());
    m_gathered.resize(static_cast<Eigen::Index>(m_rows.size()));
    for (std::size_t i = 0; i < m_rows.size(); ++i) m_gathered[static_cast<Eigen::Index>(i)] = y[static_cast<std::size_t>(m_rows[i])];
    m_g_vector.resize(s);
    if (old > 0) m_g_vector.head(old) = (m_x.transpose() * m_gathered).cast<double>();
    for (std::size_t j = 0; j < m_new.size(); ++j) m_g_vector[old + static_cast<Eigen::Index>(j)] = r[m_new[j]];
    m_s = m_c.solve(m_d * m_g_vector);
    if (old > 0) {
        m_gathered.noalias() = m_x * m_s.head(old).cast<float>();
        for (std::size_t i = 0; i < m_rows.size(); ++i) y[static_cast<std::size_t>(m_rows[i])] -= m_gathered[static_cast<Eigen::Index>(i)];
    }
    z_new.resize(static_cast<Eigen::Index>(m_new.size()));
    for (std::size_t j = 0; j < m_new.size(); ++j) z_new[static_cast<Eigen::Index>(j)] = r[m_new[j]] - m_s[old + static_cast<Eigen::Index>(j)];
}

void FactorCorrection::add_new(const Eigen::VectorXd& z_new, Eigen::VectorXd& z) const
{
    for (std::size_t j = 0; j < m_new.size(); ++j) z[m_new[j]] = z_new[static_cast<Eigen::Index>(j)];
}

double FactorCorrection::apply_flops() const
{
    const double s = static_cast<double>(dofs());
    return 4.0 * static_cast<double>(m_rows.size()) * static_cast<double>(m_old.size()) + 4.0 * s * s;
}

} // namespace vox::fem
