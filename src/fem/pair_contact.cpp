#include "fem/pair_contact.hpp"

#include <algorithm>
#include <stdexcept>
#include <string>
#include <tuple>

namespace vox::fem {

void add_term(std::vector<BlockWeight>& terms, std::uint32_t block, double weight)
{
    const auto it = std::find_if(terms.begin(), terms.end(), [&](const BlockWeight& t) { return t.block == block; });
    if (it == terms.end()) terms.push_back({block, weight});
    else it->weight += weight;
}

bool add_to_matrix(const PairContact& p, double scale, const std::vector<unsigned char>& fixed, SystemMatrix& matrix)
{
    if (p.stiffness_n_per_m == 0.0) return false;
    const int* outer = matrix.outerIndexPtr();
    const int* inner = matrix.innerIndexPtr();
    double* values = matrix.valuePtr();
    // The first entry of block (a, b), or -1.
    auto block_at = [&](std::uint32_t a, std::uint32_t b) -> std::ptrdiff_t {
        const int* begin = inner + outer[3 * std::size_t{a}];
        const int* end = inner + outer[3 * std::size_t{a} + 1];
        const int* at = std::lower_bound(begin, end, static_cast<int>(3 * b));
        return at != end && *at == static_cast<int>(3 * b) ? at - inner : -1;
    };
    std::vector<std::ptrdiff_t> at(p.terms.size() * p.terms.size());
    for (std::size_t a = 0; a < p.terms.size(); ++a)
        for (std::size_t b = 0; b < p.terms.size(); ++b)
            if ((at[a * p.terms.size() + b] = block_at(p.terms[a].block, p.terms[b].block)) < 0) return false;
    const Eigen::Matrix3d nn = scale * p.stiffness_n_per_m * p.normal * p.normal.transpose();
    for (std::size_t a = 0; a < p.terms.size(); ++a) {
        const std::size_t row = 3 * std::size_t{p.terms[a].block};
        const int row_length = outer[row + 1] - outer[row];
        for (std::size_t b = 0; b < p.terms.size(); ++b) {
            const std::size_t column = 3 * std::size_t{p.terms[b].block};
            const double w = p.terms[a].weight * p.terms[b].weight;
            for (int r = 0; r < 3; ++r)
                for (int c = 0; c < 3; ++c)
                    if (!fixed[row + static_cast<std::size_t>(r)] && !fixed[column + static_cast<std::size_t>(c)])
                        values[at[a * p.terms.size() + b] + r * row_length + c] += w * nn(r, c);
        }
    }
    return true;
}

void PairContacts::set(std::vector<PairContact> pairs, const std::vector<Eigen::Vector3d>& x)
{
    for (const PairContact& p : pairs) {
        if (!(p.stiffness_n_per_m >= 0.0)) throw std::invalid_argument("PairContacts::set: negative stiffness");
        for (const BlockWeight& t : p.terms)
            if (t.block >= x.size()) throw std::invalid_argument("PairContacts::set: no block " + std::to_string(t.block));
    }
    m_pairs = std::move(pairs);
    m_gap_set.resize(m_pairs.size());
    m_waiting.assign(m_pairs.size(), {0.0, 0.0});
    for (std::size_t i = 0; i < m_pairs.size(); ++i) {
        m_gap_set[i] = gap(m_pairs[i], x);
        if (!m_pairs[i].waiting) continue;
        m_waiting[i] = {m_pairs[i].force_n, m_pairs[i].stiffness_n_per_m};
        m_pairs[i].force_n = m_pairs[i].stiffness_n_per_m = 0.0;
    }
}

double PairContacts::gap(const PairContact& p, const std::vector<Eigen::Vector3d>& x) const
{
    double g = 0.0;
    for (const BlockWeight& t : p.terms) g += t.weight * p.normal.dot(x[t.block]);
    return g;
}

void PairContacts::add_forces(const std::vector<Eigen::Vector3d>& x, Eigen::VectorXd& f) const
{
    for (std::size_t i = 0; i < m_pairs.size(); ++i) {
        const PairContact& p = m_pairs[i];
        const double force = force_at(i, x);
        for (const BlockWeight& t : p.terms) f.segment<3>(3 * static_cast<Eigen::Index>(t.block)) += t.weight * force * p.normal;
    }
}

void PairContacts::add_product(const Eigen::VectorXd& v, double scale, const std::vector<unsigned char>& fixed, Eigen::VectorXd& out,
                               const std::vector<unsigned char>* skip) const
{
    for (std::size_t i = 0; i < m_pairs.size(); ++i) {
        if (skip && (*skip)[i]) continue;
        const PairContact& p = m_pairs[i];
        double s = 0.0;
        for (const BlockWeight& t : p.terms) s += t.weight * p.normal.dot(v.segment<3>(3 * static_cast<Eigen::Index>(t.block)));
        s *= scale * p.stiffness_n_per_m;
        for (const BlockWeight& t : p.terms)
            for (int a = 0; a < 3; ++a) {
                const std::size_t dof = 3 * std::size_t{t.block} + static_cast<std::size_t>(a);
                if (!fixed[dof]) out[static_cast<Eigen::Index>(dof)] += s * t.weight * p.normal[a];
            }
    }
}

void PairContacts::add_diagonal(double scale, Eigen::VectorXd& d, const std::vector<unsigned char>* skip) const
{
    for (std::size_t i = 0; i < m_pairs.size(); ++i) {
        if (skip && (*skip)[i]) continue;
        const PairContact& p = m_pairs[i];
        for (const BlockWeight& t : p.terms)
            d.segment<3>(3 * static_cast<Eigen::Index>(t.block)).array() +=
                scale * p.stiffness_n_per_m * t.weight * t.weight * p.normal.array().square();
    }
}

PairForceSum PairContacts::force_sum(const std::vector<Eigen::Vector3d>& x, std::size_t first, std::size_t last) const
{
    PairForceSum sum;
    for (std::size_t i = first; i < std::min(last, m_pairs.size()); ++i) {
        const double f = std::max(0.0, force_at(i, x));
        sum.magnitude_n += f;
        sum.vector_n += f * m_pairs[i].normal;
    }
    return sum;
}

std::vector<std::size_t> PairContacts::pulling(const std::vector<Eigen::Vector3d>& x) const
{
    std::vector<std::size_t> out;
    for (std::size_t i = 0; i < m_pairs.size(); ++i)
        if (m_pairs[i].stiffness_n_per_m != 0.0 && force_at(i, x) < 0.0) out.push_back(i);
    return out;
}

std::vector<Eigen::Vector3d> PairContacts::step_end(const std::vector<Eigen::Vector3d>& x, double dt, const Eigen::VectorXd& v)
{
    std::vector<Eigen::Vector3d> end(x.size());
    for (std::size_t b = 0; b < x.size(); ++b) end[b] = x[b] + dt * v.segment<3>(3 * static_cast<Eigen::Index>(b));
    return end;
}

void PairContacts::release(const std::vector<std::size_t>& which)
{
    for (std::size_t i : which) m_pairs[i].force_n = m_pairs[i].stiffness_n_per_m = 0.0;
}

std::vector<std::size_t> PairContacts::arriving(const std::vector<Eigen::Vector3d>& x) const
{
    std::vector<std::size_t> out;
    for (std::size_t i = 0; i < m_pairs.size(); ++i)
        if (m_pairs[i].waiting && m_waiting[i].first - m_waiting[i].second * (gap(m_pairs[i], x) - m_gap_set[i]) > 0.0) out.push_back(i);
    return out;
}

void PairContacts::activate(const std::vector<std::size_t>& which)
{
    for (std::size_t i : which) {
        m_pairs[i].waiting = false;
        std::tie(m_pairs[i].force_n, m_pairs[i].stiffness_n_per_m) = m_waiting[i];
    }
}

std::size_t PairContacts::settle(const std::vector<Eigen::Vector3d>& x)
{
    const std::vector<std::size_t> out = pulling(x), in = arriving(x);
    release(out);
    activate(in);
    return out.size() + in.size();
}

double PairContacts::potential(const std::vector<Eigen::Vector3d>& x) const
{
    double u = 0.0;
    for (std::size_t i = 0; i < m_pairs.size(); ++i) {
        const double d = gap(m_pairs[i], x) - m_gap_set[i];
        u += -m_pairs[i].force_n * d + 0.5 * m_pairs[i].stiffness_n_per_m * d * d;
    }
    return u;
}

double PairContacts::stiffness_product(const std::vector<Eigen::Vector3d>& v) const
{
    double sum = 0.0;
    for (const PairContact& p : m_pairs) {
        const double s = gap(p, v);
        sum += p.stiffness_n_per_m * s * s;
    }
    return sum;
}

} // namespace vox::fem
