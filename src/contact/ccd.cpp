#include "contact/ccd.hpp"

#include "contact/interval.hpp"

#include <limits>

namespace vox::contact {
namespace {

/// The input points as intervals (their own rounding included), at both ends of the step.
struct Motion {
    std::array<IVec3, 4> start, end;
};

/// An input point as an interval vector, its own rounding included.
IVec3 lift(const Eigen::Vector3d& p, double ulps)
{
    return IVec3{Interval::widened(p.x(), p.x(), ulps), Interval::widened(p.y(), p.y(), ulps), Interval::widened(p.z(), p.z(), ulps)};
}

Motion motion(const std::array<Eigen::Vector3d, 4>& at0, const std::array<Eigen::Vector3d, 4>& at1, double ulps)
{
    Motion m;
    for (std::size_t i = 0; i < 4; ++i) {
        m.start[i] = lift(at0[i], ulps);
        m.end[i] = lift(at1[i], ulps);
    }
    return m;
}

/// Point i's position over the time interval t: start + t (end - start).
IVec3 at(const Motion& m, int i, const Interval& t)
{
    const IVec3& s = m.start[static_cast<std::size_t>(i)];
    return s + t * (m.end[static_cast<std::size_t>(i)] - s);
}

/// The earliest time in [lo, hi] that `excluded` (true when no contact is possible anywhere in
/// the time interval it is given) cannot rule out: the start of the first interval that survives
/// max_depth halvings, taking earlier halves first; infinity when every interval is ruled out. A
/// template, not a std::function, so that the haptic loop's calls never allocate.
/// Intervals starting at or after `before` are not searched (an earlier contact is known).
template <class Excluded>
double first_surviving(const Excluded& excluded, double lo, double hi, int depth, int max_depth, double before)
{
    if (lo >= before || excluded(Interval(lo, hi))) return std::numeric_limits<double>::infinity();
    if (depth == max_depth) return lo;
    const double mid = 0.5 * (lo + hi);
    const double early = first_surviving(excluded, lo, mid, depth + 1, max_depth, before);
    return early <= mid ? early : first_surviving(excluded, mid, hi, depth + 1, max_depth, before);
}

/// The boxes of the two groups of points (indices [0, split) and [split, 4)) over t do not meet.
bool boxes_apart(const std::array<IVec3, 4>& p, int split)
{
    auto apart = [&](auto member) {
        double lo_a = std::numeric_limits<double>::infinity(), hi_a = -lo_a, lo_b = lo_a, hi_b = -lo_a;
        for (int i = 0; i < 4; ++i) {
            const Interval& c = member(p[static_cast<std::size_t>(i)]);
            double& lo = i < split ? lo_a : lo_b;
            double& hi = i < split ? hi_a : hi_b;
            lo = std::min(lo, c.lo);
            hi = std::max(hi, c.hi);
        }
        return hi_a < lo_b || hi_b < lo_a;
    };
    return apart([](const IVec3& v) -> const Interval& { return v.x; }) || apart([](const IVec3& v) -> const Interval& { return v.y; }) ||
           apart([](const IVec3& v) -> const Interval& { return v.z; });
}

/// Tang, Curtis, Yoon and Manocha 2010's non-penetration filter for the coplanarity condition:
/// q(t) . (b(t) x c(t)) is a cubic whose Bernstein coefficients over [0, 1] are the blossoms of
/// the three linear factors; when all four are of one strict sign the four points are never
/// coplanar in the step. Returns true when the filter proves that.
bool never_coplanar(const IVec3& q0, const IVec3& q1, const IVec3& b0, const IVec3& b1, const IVec3& c0, const IVec3& c1)
{
    const Interval third = Interval::widened(1.0 / 3.0, 1.0 / 3.0);
    const Interval k0 = dot(q0, cross(b0, c0));
    const Interval k3 = dot(q1, cross(b1, c1));
    const Interval k1 = third * (dot(q1, cross(b0, c0)) + dot(q0, cross(b1, c0)) + dot(q0, cross(b0, c1)));
    const Interval k2 = third * (dot(q0, cross(b1, c1)) + dot(q1, cross(b0, c1)) + dot(q1, cross(b1, c0)));
    const bool positive = k0.lo > 0 && k1.lo > 0 && k2.lo > 0 && k3.lo > 0;
    const bool negative = k0.hi < 0 && k1.hi < 0 && k2.hi < 0 && k3.hi < 0;
    return positive || negative;
}

} // namespace

double vertex_face_toi(const std::array<Eigen::Vector3d, 4>& at0, const std::array<Eigen::Vector3d, 4>& at1, const CcdOptions& options,
                       double before) noexcept
{
    const Motion m = motion(at0, at1, options.input_ulps);
    if (never_coplanar(m.start[0] - m.start[1], m.end[0] - m.end[1], m.start[2] - m.start[1], m.end[2] - m.end[1],
                       m.start[3] - m.start[1], m.end[3] - m.end[1]))
        return std::numeric_limits<double>::infinity();
    const auto excluded = [&m](const Interval& t) {
        const std::array<IVec3, 4> p{at(m, 0, t), at(m, 1, t), at(m, 2, t), at(m, 3, t)};
        if (boxes_apart(p, 1)) return true;
        const IVec3 b = p[2] - p[1], c = p[3] - p[1], q = p[0] - p[1];
        const IVec3 n = cross(b, c);
        if (!dot(q, n).contains_zero()) return true; // never coplanar in t
        // Inside the triangle: q on the inner side of each edge (sign against the normal).
        if (dot(cross(b, q), n).below_zero()) return true;
        if (dot(cross(q, c), n).below_zero()) return true;
        return dot(cross(c - b, q - b), n).below_zero();
    };
    return first_surviving(excluded, 0.0, 1.0, 0, options.max_depth, before);
}

double edge_edge_toi(const std::array<Eigen::Vector3d, 4>& at0, const std::array<Eigen::Vector3d, 4>& at1, const CcdOptions& options,
                     double before) noexcept
{
    const Motion m = motion(at0, at1, options.input_ulps);
    // Coplanarity of d = b0 - a0 with ea and eb: the same cubic filter.
    if (never_coplanar(m.start[2] - m.start[0], m.end[2] - m.end[0], m.start[1] - m.start[0], m.end[1] - m.end[0],
                       m.start[3] - m.start[2], m.end[3] - m.end[2]))
        return std::numeric_limits<double>::infinity();
    const auto excluded = [&m](const Interval& t) {
        const std::array<IVec3, 4> p{at(m, 0, t), at(m, 1, t), at(m, 2, t), at(m, 3, t)};
        if (boxes_apart(p, 2)) return true;
        const IVec3 ea = p[1] - p[0], eb = p[3] - p[2], d = p[2] - p[0];
        const IVec3 n = cross(ea, eb);
        if (!dot(d, n).contains_zero()) return true; // never coplanar in t
        // Crossing point a0 + s ea = b0 + u eb with s, u in [0, 1]: s |n|^2 = (d x eb) . n,
        // u |n|^2 = (d x ea) . n.
        const Interval nn = dot(n, n);
        const Interval s = dot(cross(d, eb), n), u = dot(cross(d, ea), n);
        return s.below_zero() || (nn - s).below_zero() || u.below_zero() || (nn - u).below_zero();
    };
    return first_surviving(excluded, 0.0, 1.0, 0, options.max_depth, before);
}

namespace {

/// Where in [0, 1] a coplanarity condition linear in t, value + t rate, is zero: the bound of its
/// root, empty (lo > hi) when it has none there; `exact` false when the rate may be zero or the
/// bound is wider than the general search would resolve (the general query must answer).
struct Root {
    double lo = 1.0, hi = 0.0;
    bool exact = false;
};

Root linear_root(const Interval& value, const Interval& rate, const CcdOptions& options)
{
    if (rate.contains_zero()) return {};
    const Interval t = Interval(0.0) - value / rate;
    Root r{std::max(t.lo, 0.0), std::min(t.hi, 1.0), true};
    r.exact = r.lo > r.hi || r.hi - r.lo <= std::ldexp(1.0, -options.max_depth);
    return r;
}

} // namespace

double translating_vertex_face_toi(const Eigen::Vector3d& vertex, const Eigen::Vector3d& move, const std::array<Eigen::Vector3d, 3>& face,
                                   const CcdOptions& options, double before) noexcept
{
    const double ulps = options.input_ulps;
    const IVec3 p = lift(vertex, ulps), d = lift(move, ulps), a = lift(face[0], ulps), b = lift(face[1], ulps) - a, c = lift(face[2], ulps) - a;
    const IVec3 n = cross(b, c);
    // (p + t d - a) . n = 0.
    const Root root = linear_root(dot(p - a, n), dot(d, n), options);
    if (!root.exact)
        return vertex_face_toi({vertex, face[0], face[1], face[2]}, {vertex + move, face[0], face[1], face[2]}, options, before);
    if (root.lo > root.hi || root.lo >= before) return std::numeric_limits<double>::infinity();
    // Inside the triangle while on its plane, as the general query's conditions (corner a at 0).
    const IVec3 q = p + Interval(root.lo, root.hi) * d - a;
    if (dot(cross(b, q), n).below_zero() || dot(cross(q, c), n).below_zero() || dot(cross(c - b, q - b), n).below_zero())
        return std::numeric_limits<double>::infinity();
    return root.lo;
}

double translating_edge_edge_toi(const std::array<Eigen::Vector3d, 2>& edge, const Eigen::Vector3d& move, const std::array<Eigen::Vector3d, 2>& other,
                                 const CcdOptions& options, double before) noexcept
{
    const double ulps = options.input_ulps;
    const IVec3 a0 = lift(edge[0], ulps), ea = lift(edge[1], ulps) - a0, d = lift(move, ulps), b0 = lift(other[0], ulps),
                eb = lift(other[1], ulps) - b0;
    const IVec3 n = cross(ea, eb);
    // (b0 - a0 - t d) . n = 0.
    const Root root = linear_root(Interval(0.0) - dot(b0 - a0, n), dot(d, n), options);
    if (!root.exact)
        return edge_edge_toi({edge[0], edge[1], other[0], other[1]}, {edge[0] + move, edge[1] + move, other[0], other[1]}, options, before);
    if (root.lo > root.hi || root.lo >= before) return std::numeric_limits<double>::infinity();
    // The crossing point within both edges, as the general query's conditions.
    const IVec3 w = b0 - (a0 + Interval(root.lo, root.hi) * d);
    const Interval nn = dot(n, n), s = dot(cross(w, eb), n), u = dot(cross(w, ea), n);
    if (s.below_zero() || (nn - s).below_zero() || u.below_zero() || (nn - u).below_zero()) return std::numeric_limits<double>::infinity();
    return root.lo;
}

bool vertex_face_ccd(const std::array<Eigen::Vector3d, 4>& at0, const std::array<Eigen::Vector3d, 4>& at1, const CcdOptions& options)
{
    return vertex_face_toi(at0, at1, options) <= 1.0;
}

bool edge_edge_ccd(const std::array<Eigen::Vector3d, 4>& at0, const std::array<Eigen::Vector3d, 4>& at1, const CcdOptions& options)
{
    return edge_edge_toi(at0, at1, options) <= 1.0;
}

} // namespace vox::contact
