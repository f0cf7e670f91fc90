#include "isxfem/cut_tetrahedron.hpp"

#include "isxfem/simplex_rule.hpp"

#include <Eigen/LU>

#include <algorithm>
#include <cmath>

namespace vox::isxfem {
namespace {

const std::array<Eigen::Vector3d, 4> k_vertex{Eigen::Vector3d(0, 0, 0), Eigen::Vector3d(1, 0, 0), Eigen::Vector3d(0, 1, 0),
                                              Eigen::Vector3d(0, 0, 1)};

/// A point on an edge of the reference tetrahedron: vertex `base` moved by the fraction u <= 1/2
/// towards vertex `other` (u = 0: the vertex itself).
struct EdgePoint {
    int base = 0, other = 0;
    double u = 0.0;
    [[nodiscard]] Eigen::Vector3d position() const { return k_vertex[static_cast<std::size_t>(base)] + u * direction(); }
    [[nodiscard]] Eigen::Vector3d direction() const
    {
        return k_vertex[static_cast<std::size_t>(other)] - k_vertex[static_cast<std::size_t>(base)];
    }
};

/// p - q, each term exact or a product with one rounding: accurate relative to its own size.
Eigen::Vector3d difference(const EdgePoint& p, const EdgePoint& q)
{
    return (k_vertex[static_cast<std::size_t>(p.base)] - k_vertex[static_cast<std::size_t>(q.base)]) + p.u * p.direction() -
           q.u * q.direction();
}

EdgePoint vertex(int k) { return {k, k, 0.0}; }

/// Where the cut crosses edge (a, b), phi[a] < 0 <= phi[b], from the nearer end.
EdgePoint crossing(const std::array<double, 4>& phi, int a, int b)
{
    const double from_a = phi[static_cast<std::size_t>(a)] / (phi[static_cast<std::size_t>(a)] - phi[static_cast<std::size_t>(b)]);
    if (from_a <= 0.5) return {a, b, from_a};
    return {b, a, phi[static_cast<std::size_t>(b)] / (phi[static_cast<std::size_t>(b)] - phi[static_cast<std::size_t>(a)])};
}

/// The tetrahedron of four points. Its volume comes from the path through the points whose
/// steps have the smallest product of lengths: a sliver's short steps then stay separate
/// columns of the determinant instead of cancelling between two long ones.
Piece piece(const std::array<EdgePoint, 4>& p)
{
    std::array<int, 4> order{0, 1, 2, 3};
    double best = INFINITY;
    Eigen::Matrix3d steps = Eigen::Matrix3d::Zero();
    std::array<int, 4> chosen = order;
    do {
        Eigen::Matrix3d s;
        for (int k = 0; k < 3; ++k)
            s.col(k) = difference(p[static_cast<std::size_t>(order[static_cast<std::size_t>(k + 1)])],
                                  p[static_cast<std::size_t>(order[static_cast<std::size_t>(k)])]);
        const double size = s.col(0).norm() * s.col(1).norm() * s.col(2).norm();
        if (size < best) {
            best = size;
            steps = s;
            chosen = order;
        }
    } while (std::next_permutation(order.begin(), order.end()));
    Piece out;
    out.corner = p[static_cast<std::size_t>(chosen[0])].position();
    out.edges.col(0) = steps.col(0);
    out.edges.col(1) = steps.col(0) + steps.col(1);
    out.edges.col(2) = steps.col(0) + steps.col(1) + steps.col(2);
    out.volume = std::abs(steps.determinant()) / 6.0;
    return out;
}

/// The prism between triangles a and b (a[i] joined to b[i]) as three tetrahedra.
void add_prism(const std::array<EdgePoint, 3>& a, const std::array<EdgePoint, 3>& b, std::vector<Piece>& out)
{
    out.push_back(piece({a[0], a[1], a[2], b[2]}));
    out.push_back(piece({a[0], a[1], b[1], b[2]}));
    out.push_back(piece({a[0], b[0], b[1], b[2]}));
}

double total(const std::vector<Piece>& pieces)
{
    double v = 0.0;
    for (const Piece& p : pieces) v += p.volume;
    return v;
}

} // namespace

double CutSides::negative_volume() const { return total(negative); }
double CutSides::positive_volume() const { return total(positive); }

CutSides split_reference_tetrahedron(const std::array<double, 4>& phi)
{
    std::vector<int> neg, pos;
    for (int k = 0; k < 4; ++k) (phi[static_cast<std::size_t>(k)] < 0.0 ? neg : pos).push_back(k);
    CutSides sides;
    if (neg.empty() || pos.empty()) {
        (neg.empty() ? sides.positive : sides.negative).push_back(whole_tetrahedron());
        return sides;
    }
    auto cross = [&](int a, int b) { return phi[static_cast<std::size_t>(a)] < 0.0 ? crossing(phi, a, b) : crossing(phi, b, a); };
    if (neg.size() == 2) {
        const int p = neg[0], q = neg[1], r = pos[0], s = pos[1];
        add_prism({vertex(p), cross(p, r), cross(p, s)}, {vertex(q), cross(q, r), cross(q, s)}, sides.negative);
        add_prism({vertex(r), cross(p, r), cross(q, r)}, {vertex(s), cross(p, s), cross(q, s)}, sides.positive);
        return sides;
    }
    const bool lone_negative = neg.size() == 1;
    const int p = lone_negative ? neg[0] : pos[0];
    const std::vector<int>& rest = lone_negative ? pos : neg;
    const int q = rest[0], r = rest[1], s = rest[2];
    std::vector<Piece>& lone = lone_negative ? sides.negative : sides.positive;
    std::vector<Piece>& other = lone_negative ? sides.positive : sides.negative;
    lone.push_back(piece({vertex(p), cross(p, q), cross(p, r), cross(p, s)}));
    add_prism({cross(p, q), cross(p, r), cross(p, s)}, {vertex(q), vertex(r), vertex(s)}, other);
    return sides;
}

Piece whole_tetrahedron() { return piece({vertex(0), vertex(1), vertex(2), vertex(3)}); }

Eigen::VectorXd monomial_moments(const std::vector<Piece>& pieces, int p, double centre, double scale)
{
    const std::vector<std::array<int, 3>> exponents = monomial_exponents(p);
    const SimplexRule rule = grundmann_moeller_tetrahedron(std::max(0, p / 2)); // degree 2s + 1 >= p
    Eigen::VectorXd m = Eigen::VectorXd::Zero(static_cast<Eigen::Index>(exponents.size()));
    for (const Piece& piece : pieces) {
        const double jacobian = 6.0 * piece.volume;
        if (jacobian == 0.0) continue;
        for (std::size_t q = 0; q < rule.points.size(); ++q) {
            const Eigen::Vector3d x = scale * (piece.corner + piece.edges * rule.points[q] - Eigen::Vector3d::Constant(centre));
            for (std::size_t j = 0; j < exponents.size(); ++j)
                m[static_cast<Eigen::Index>(j)] += jacobian * rule.weights[q] * monomial(exponents[j], x);
        }
    }
    return m;
}

} // namespace vox::isxfem
