#include "contact/proxy.hpp"

#include <Eigen/Cholesky>

#include <algorithm>
#include <array>
#include <cmath>

namespace vox::contact {
namespace {

/// A point this near its depth bound, mm, is at it.
constexpr double k_at_bound_mm = 1e-4;

} // namespace

double depth_bound_mm(const ToolShape& shape, double margin_mm) noexcept
{
    const double wanted = std::max(0.5, margin_mm + 0.02);
    const double half = margin_mm - shape.signed_distance(Eigen::Vector3d::Zero()); // the pushing shape's depth at its origin
    return half > 0.0 ? std::min(wanted, 0.9 * half) : wanted;
}

double deepest_point_mm(const PlacedShape& tool, double margin_mm, const SurfacePoints& points) noexcept
{
    double deepest = 0.0;
    points.for_each_point_near(tool.world_bounds(margin_mm), [&](std::size_t i) {
        if (points.is_replaced(i)) return;
        deepest = std::max(deepest, margin_mm - tool.signed_distance(points.positions_mm[i]));
    });
    return deepest;
}

double load_scale(const Eigen::Vector3d& coupling_n, const Eigen::Vector3d& contact_n, double deepest_mm, double bound_mm) noexcept
{
    double scale = 1.0;
    const double f2 = contact_n.squaredNorm();
    if (f2 > 0.0) scale = std::max(scale, -coupling_n.dot(contact_n) / f2); // the push along the contact, over the contact
    if (bound_mm > 0.0) scale = std::max(scale, deepest_mm / bound_mm);
    return std::isfinite(scale) ? scale : 1.0;
}

ProxyMover::ProxyMover(const ToolShape& shape, const ContactParameters& contact, std::size_t point_capacity)
    : m_contact(contact), m_bound(depth_bound_mm(shape, contact.margin_mm)), m_sweep(shape, contact.margin_mm, point_capacity),
      m_candidates(point_capacity), m_limit(point_capacity)
{
}

double ProxyMover::bounded_share(const PlacedShape& proxy, const Eigen::Vector3d& step, const SurfacePoints& points,
                                 std::span<const double> distance, Eigen::Vector3d& blocking) noexcept
{
    blocking.setZero();
    const double length = step.norm();
    if (!(length > 0.0)) return 1.0;
    const double margin = m_contact.margin_mm;
    PlacedShape end = proxy;
    end.position += step;
    Eigen::AlignedBox3d box = proxy.world_bounds(margin);
    box.extend(end.world_bounds(margin));
    // A point whose slack (the move before it can touch at all) outlasts the move cannot reach its
    // bound; a distance to a fixed point is convex along the move, so the move's ends bound it.
    const double spent = std::max(points.slack_spent(proxy, margin), points.slack_spent(end, margin));
    std::size_t n = 0;
    points.for_each_point_near(box, [&](std::size_t i) {
        if (points.is_replaced(i) || n >= m_candidates.size()) return;
        // The contact measured most points' distances at the proxy already (+infinity: not).
        const double measured = i < distance.size() ? distance[i] : INFINITY;
        const double depth = margin - (measured < INFINITY ? measured : proxy.signed_distance(points.positions_mm[i]));
        const double limit = std::max(m_bound, depth); // a point already deeper (the material came in) may not go deeper
        if (depth + length <= limit) return;            // 1-Lipschitz: it cannot reach its bound over this move
        m_candidates[n] = static_cast<std::uint32_t>(i);
        m_limit[n] = limit;
        ++n;
    }, spent);
    if (n == 0) return 1.0;
    // A point blocks at its bound only if the move takes it deeper there: a move along the
    // bound's tangent (a slide) leaves it, since the tool is convex.
    const double tangent = 1e-9 * length;
    double first = 1.0;
    if (proxy.shape->kind() != ToolShape::Kind::mesh) {
        // A convex tool: each point's depth is concave along the move, so its gap to the bound,
        // g(t), is convex, and Newton's method from t = 0 where g falls reaches the first root
        // from below without passing it (a handful of distances a point).
        PlacedShape at = proxy;
        for (std::size_t c = 0; c < n; ++c) {
            double t = 0.0;
            for (int k = 0; k < 32; ++k) {
                at.position = proxy.position + t * step;
                Eigen::Vector3d gradient;
                const double g = m_limit[c] - (margin - at.signed_distance(points.positions_mm[m_candidates[c]], &gradient));
                const double falling = gradient.dot(step); // -dg/dt
                if (g <= k_at_bound_mm) {
                    if (falling > tangent) {
                        first = t;
                        blocking = gradient;
                    }
                    break;
                }
                if (falling <= tangent) break; // it only moves away from its bound from here
                t += g / falling;
                if (t >= first) break; // another point blocks earlier
            }
        }
        return first;
    }
    // A mesh tool (its distance need not be convex): conservative advancement, since no point
    // closes a gap g to its bound before the tool has moved g.
    double t = 0.0;
    PlacedShape at = proxy;
    for (int k = 0; k < 64 && n > 0; ++k) {
        at.position = proxy.position + t * step;
        double gap = INFINITY;
        for (std::size_t c = 0; c < n;) {
            Eigen::Vector3d gradient;
            const double g = m_limit[c] - (margin - at.signed_distance(points.positions_mm[m_candidates[c]], &gradient));
            if (g <= k_at_bound_mm) {
                if (gradient.dot(step) > tangent) {
                    blocking = gradient;
                    return t;
                }
                m_candidates[c] = m_candidates[n - 1]; // leaving its bound (taken as for a convex tool)
                m_limit[c] = m_limit[n - 1];
                --n;
                continue;
            }
            gap = std::min(gap, g);
            ++c;
        }
        if (n == 0) break;
        t += gap / length;
        if (t >= 1.0) return 1.0;
    }
    return n == 0 ? 1.0 : t; // grazing after 64 advances: as far as is proven safe
}

Eigen::Vector3d ProxyMover::move(PlacedShape& proxy, const Eigen::Vector3d& step, const SurfacePoints& points, std::span<const double> distance) noexcept
{
    m_blocked = false;
    const Eigen::Vector3d start = proxy.position;
    Eigen::Vector3d rest = step;
    std::array<Eigen::Vector3d, 3> planes; // blocking directions met so far (unit)
    int plane_count = 0;
    for (int k = 0; k < 6 && rest.squaredNorm() > 1e-18; ++k) {
        Eigen::Vector3d blocking;
        const std::span<const double> measured = k == 0 ? distance : std::span<const double>{}; // at the proxy where it started
        const double t = bounded_share(proxy, rest, points, measured, blocking);
        PlacedShape to = proxy;
        to.position += t * rest;
        // What passes between points (a thin blade through a face): the tool's mesh against the
        // triangles. Its stop has no normal to slide along: the proxy stays there this step.
        const double t_mesh = m_sweep.first_stop(proxy, to, points, measured);
        if (t_mesh < 1.0) {
            proxy.position += t_mesh * t * rest;
            m_blocked = true;
            break;
        }
        proxy.position = to.position;
        if (t >= 1.0) break;
        m_blocked = true;
        if (blocking.squaredNorm() == 0.0) break;
        // Slide: what is left of the step, without its part into the blocking directions met
        // (each a half-space: a part away from one is kept), projected in turn until it goes
        // into none; the three most recent are kept.
        if (plane_count == 3) {
            planes[0] = planes[1];
            planes[1] = planes[2];
            plane_count = 2;
        }
        planes[plane_count++] = blocking.normalized();
        rest *= 1.0 - t;
        for (int round = 0; round < 8; ++round) {
            bool into = false;
            for (int p = 0; p < plane_count; ++p)
                if (const double d = rest.dot(planes[p]); d > 1e-12 * rest.norm()) {
                    rest -= d * planes[p];
                    into = true;
                }
            if (!into) break;
        }
        for (int p = 0; p < plane_count; ++p)
            if (rest.dot(planes[p]) > 1e-9 * rest.norm()) rest.setZero(); // a corner: no way on
    }
    return proxy.position - start;
}

Eigen::Vector3d ProxyMover::step(PlacedShape& proxy, const Eigen::Vector3d& driver, double coupling_n_per_mm, const ContactTotals& contact,
                                 const SurfacePoints& points, std::span<const double> distance) noexcept
{
    const Eigen::Matrix3d a = coupling_n_per_mm * Eigen::Matrix3d::Identity() + contact.stiffness_n_per_mm;
    const Eigen::Vector3d residual = coupling_n_per_mm * (driver - proxy.position) + contact.force_on_tool_n;
    Eigen::Vector3d s = a.ldlt().solve(residual);
    const double limit = std::max(m_contact.margin_mm, 0.05);
    if (contact.area_mm2 > 0.0 && s.norm() > limit) s *= limit / s.norm();
    if (!s.allFinite()) return Eigen::Vector3d::Zero();
    return move(proxy, s, points, distance);
}

ContactTotals ProxyMover::settle(PlacedShape& proxy, const Eigen::Vector3d& driver, double coupling_n_per_mm, const SurfacePoints& points,
                                 int iterations)
{
    if (m_distance.size() < points.count) m_distance.resize(points.count);
    const std::span<double> distance(m_distance.data(), points.count);
    for (int k = 0; k < iterations; ++k) {
        const ContactTotals contact = penalty_totals(proxy, m_contact, points, false, distance);
        if (step(proxy, driver, coupling_n_per_mm, contact, points, distance).norm() < 1e-3) break;
    }
    return penalty_totals(proxy, m_contact, points, true);
}

} // namespace vox::contact
