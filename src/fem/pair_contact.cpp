#include "fem/pair_contact.hpp"

#include <algorithm>
#include <stdexcept>
#include <string>

namespace vox::fem {

void add_term(std::vector<BlockWeight>& terms, std::uint32_t block, double weight)
{
    const auto it = std::find_if(terms.begin(), terms.end(), [&](const BlockWeight& t) { return t.block == block; });
    if (it == terms.end()) terms.push_back({block, weight});
    else it->weight += weight;
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
    for (std::size_t i = 0; i < m_pairs.size(); ++i) m_gap_set[i] = gap(m_pairs[i], x);
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

void PairContacts::add_product(const Eigen::VectorXd& v, double scale, const std::vector<unsigned char>& fixed, Eigen::VectorXd& out) const
{
    for (const PairContact& p : m_pairs) {
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

void PairContacts::add_diagonal(double scale, Eigen::VectorXd& d) const
{
    for (const PairContact& p : m_pairs)
        for (const BlockWeight& t : p.terms)
            d.segment<3>(3 * static_cast<Eigen::Index>(t.block)).array() +=
                scale * p.stiffness_n_per_m * t.weight * t.weight * p.normal.array().square();
}

double PairContacts::total_force(const std::vector<Eigen::Vector3d>& x) const
{
    double sum = 0.0;
    for (std::size_t i = 0; i < m_pairs.size(); ++i)
        sum += std::max(0.0, force_at(i, x));
    return sum;
}

std::size_t PairContacts::release_pulling(const std::vector<Eigen::Vector3d>& x)
{
    std::size_t released = 0;
    for (std::size_t i = 0; i < m_pairs.size(); ++i) {
        PairContact& p = m_pairs[i];
        if (p.stiffness_n_per_m == 0.0 || force_at(i, x) >= 0.0) continue;
        p.force_n = p.stiffness_n_per_m = 0.0;
        ++released;
    }
    return released;
}

std::size_t PairContacts::release_pulling(const std::vector<Eigen::Vector3d>& x, double dt, const Eigen::VectorXd& v)
{
    if (m_pairs.empty()) return 0;
    std::vector<Eigen::Vector3d> end(x.size());
    for (std::size_t b = 0; b < x.size(); ++b) end[b] = x[b] + dt * v.segment<3>(3 * static_cast<Eigen::Index>(b));
    return release_pulling(end);
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
