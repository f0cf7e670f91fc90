#pragma once
// An independent reference for the cut-tetrahedron quadrature tests: both sides of a planar cut of
// the reference tetrahedron and their monomial moments, computed naively (intersection points as
// absolute coordinates, determinants of plain differences) but in quadruple precision
// (__float128, 34 digits), so a side of relative volume 1e-14 still has 20 good digits. Each side
// is integrated on its own, so checking that they add up to the whole also checks the way the
// sides are split into tetrahedra.

#include "isxfem/simplex_rule.hpp"

#include <array>
#include <vector>

namespace vox::isxfem::test {

using quad = __float128;
using QPoint = std::array<quad, 3>;

/// Moments (monomial_exponents(p) order) of the negative (phi < 0) and positive sides.
struct QuadMoments {
    std::vector<quad> negative, positive;
};

inline quad q_det(const QPoint& a, const QPoint& b, const QPoint& c, const QPoint& o)
{
    const quad u[3] = {a[0] - o[0], a[1] - o[1], a[2] - o[2]};
    const quad v[3] = {b[0] - o[0], b[1] - o[1], b[2] - o[2]};
    const quad w[3] = {c[0] - o[0], c[1] - o[1], c[2] - o[2]};
    return u[0] * (v[1] * w[2] - v[2] * w[1]) - u[1] * (v[0] * w[2] - v[2] * w[0]) + u[2] * (v[0] * w[1] - v[1] * w[0]);
}

/// Adds the moments of tetrahedron (a, b, c, d) to `m`, by the Grundmann-Moeller rule of degree 9.
inline void q_add_tet(const QPoint& a, const QPoint& b, const QPoint& c, const QPoint& d, int p, std::vector<quad>& m)
{
    static const SimplexRule rule = grundmann_moeller_tetrahedron(4);
    const quad det = q_det(b, c, d, a);
    const quad volume6 = det < 0 ? -det : det;
    const std::vector<std::array<int, 3>> e = monomial_exponents(p);
    for (std::size_t q = 0; q < rule.points.size(); ++q) {
        const quad l1 = rule.points[q].x(), l2 = rule.points[q].y(), l3 = rule.points[q].z();
        QPoint x;
        for (int k = 0; k < 3; ++k) x[k] = a[k] + l1 * (b[k] - a[k]) + l2 * (c[k] - a[k]) + l3 * (d[k] - a[k]);
        for (std::size_t j = 0; j < e.size(); ++j) {
            quad f = 1;
            for (int k = 0; k < 3; ++k)
                for (int r = 0; r < e[j][static_cast<std::size_t>(k)]; ++r) f *= x[static_cast<std::size_t>(k)];
            m[j] += volume6 * static_cast<quad>(rule.weights[q]) * f;
        }
    }
}

inline QuadMoments quad_moments(const std::array<double, 4>& phi, int p)
{
    const std::array<QPoint, 4> v{QPoint{0, 0, 0}, QPoint{1, 0, 0}, QPoint{0, 1, 0}, QPoint{0, 0, 1}};
    const std::size_t n = monomial_exponents(p).size();
    QuadMoments out{std::vector<quad>(n, 0), std::vector<quad>(n, 0)};
    std::vector<int> neg, pos;
    for (int k = 0; k < 4; ++k) (phi[static_cast<std::size_t>(k)] < 0.0 ? neg : pos).push_back(k);
    auto at = [&](int a, int b) { // the crossing on edge (a, b)
        const quad t = static_cast<quad>(phi[static_cast<std::size_t>(a)]) /
                       (static_cast<quad>(phi[static_cast<std::size_t>(a)]) - static_cast<quad>(phi[static_cast<std::size_t>(b)]));
        QPoint x;
        for (int k = 0; k < 3; ++k) x[k] = v[a][k] + t * (v[b][k] - v[a][k]);
        return x;
    };
    auto prism = [&](const std::array<QPoint, 3>& a, const std::array<QPoint, 3>& b, std::vector<quad>& m) {
        q_add_tet(a[0], a[1], a[2], b[2], p, m);
        q_add_tet(a[0], a[1], b[1], b[2], p, m);
        q_add_tet(a[0], b[0], b[1], b[2], p, m);
    };
    if (neg.empty() || pos.empty()) {
        q_add_tet(v[0], v[1], v[2], v[3], p, neg.empty() ? out.positive : out.negative);
    } else if (neg.size() == 2) {
        const int a = neg[0], b = neg[1], c = pos[0], d = pos[1];
        prism({v[a], at(a, c), at(a, d)}, {v[b], at(b, c), at(b, d)}, out.negative);
        prism({v[c], at(a, c), at(b, c)}, {v[d], at(a, d), at(b, d)}, out.positive);
    } else {
        const bool lone_negative = neg.size() == 1;
        const int a = lone_negative ? neg[0] : pos[0];
        const std::vector<int>& rest = lone_negative ? pos : neg;
        q_add_tet(v[a], at(a, rest[0]), at(a, rest[1]), at(a, rest[2]), p, lone_negative ? out.negative : out.positive);
        prism({at(a, rest[0]), at(a, rest[1]), at(a, rest[2])}, {v[rest[0]], v[rest[1]], v[rest[2]]},
              lone_negative ? out.positive : out.negative);
    }
    return out;
}

} // namespace vox::isxfem::test
