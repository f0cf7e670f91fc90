#include "contact/penalty_contact.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <utility>
#include <vector>

namespace vox::contact {
namespace {

/// One surface point against the pushing shape: its penalty force (N, on the point), its
/// stiffness (N/mm per mm of depth) and depth; false when it is outside the pushing shape.
struct PointPenalty {
    bool measured = false; ///< the point was in reach: `distance` holds its signed distance
    Eigen::Vector3d force = Eigen::Vector3d::Zero();
    Eigen::Vector3d normal = Eigen::Vector3d::Zero(); ///< the direction the point is pushed
    double stiffness = 0.0, depth = 0.0, distance = 0.0;
};

/// With `from` (the tool's pose at the start of the step), the depth is the mean over the step
/// of the penetration, linear between the two poses' depths, and the stiffness is scaled by the
/// share of the step spent inside (the derivative of that mean with the point's position).
bool point_penalty(const PlacedShape& tool, const PlacedShape* from, const ContactParameters& parameters, const Eigen::AlignedBox3d& reach,
                   const Eigen::Vector3d& p, double area, const Eigen::Vector3d& outward, PointPenalty& out) noexcept
{
    out.measured = reach.contains(p);
    if (!out.measured) return false;
    out.distance = tool.signed_distance(p, &out.normal);
    out.depth = parameters.margin_mm - out.distance;
    double inside = out.depth > 0.0 ? 1.0 : 0.0;
    if (from) out.depth = mean_penetration(parameters.margin_mm - from->signed_distance(p), out.depth, inside);
    if (!(out.depth > 0.0)) return false;
    if (outward.squaredNorm() > 0.0) out.normal = -outward; // along the object's normal (see the header)
    const double k = parameters.stiffness_n_per_mm / 100.0 * area; // per mm^2 of contact
    out.force = k * out.depth * out.normal;
    out.stiffness = k * inside;
    return true;
}

/// An edge of the object's surface against the pushing shape (the Is-XFEM sculpting paper's
/// edge-edge penalty, its equation 19): both ends outside, at both poses, but the edge between
/// them reaching in, as where a thin blade's edge lies across a face between two vertices. The
/// deepest point p = w_a a + w_b b along the edge, its depth there (integrated over the move as a point's),
/// and the area it stands for: a third of its ends' mean area (a vertex has about three edges of
/// its own) times the share of its length inside.
struct EdgePenalty {
    double w_a = 0.0, depth = 0.0, stiffness = 0.0, area = 0.0, distance = 0.0;
    Eigen::Vector3d normal = Eigen::Vector3d::Zero(), force = Eigen::Vector3d::Zero(), at = Eigen::Vector3d::Zero();
};

/// Where an edge a-b reaches deepest into a pushing shape of margin `margin` around `shape`: the
/// parameter t of its deepest point along it, and the share of its length within the margin.
struct EdgeReach {
    double t = 0.0, share = 0.0;
    double lower = 0.0; ///< when it does not reach in: a lower bound of the distance along it (>= margin)
};

/// A convex shape's signed distance is convex along the edge: f(t) = d(a + t (b - a)).
struct Probe {
    double t = 0.0, f = 0.0, slope = 0.0; ///< f and df/dt there
};

Probe probe(const PlacedShape& shape, const Eigen::Vector3d& a, const Eigen::Vector3d& b, double t) noexcept
{
    Eigen::Vector3d gradient;
    const double f = shape.signed_distance(a + t * (b - a), &gradient);
    return {t, f, gradient.dot(b - a)};
}

/// A convex shape: its lowest point by cutting planes (the tangents at the bracket's two ends meet
/// below the function, at a lower bound of it; probing there either proves the edge stays out,
/// finds the lowest point to within a micrometre of that bound, or halves the work by narrowing
/// the bracket: exact in as many probes as pieces for a box's piecewise-flat distance), then the
/// crossings of the margin on each side by Newton's method from the ends (from the outside of a
/// convex function it approaches the crossing without passing it). About ten distance
/// evaluations an edge, where a golden-section search and bisections took about ninety.
bool convex_reach(const PlacedShape& shape, const Eigen::Vector3d& a, const Eigen::Vector3d& b, double margin, EdgeReach& out) noexcept
{
    constexpr double tolerance = 1e-6; // mm of distance
    const Probe end_a = probe(shape, a, b, 0.0), end_b = probe(shape, a, b, 1.0);
    Probe lowest = end_a.f <= end_b.f ? end_a : end_b;
    out.lower = lowest.f;
    if (end_a.slope < 0.0 && end_b.slope > 0.0) { // the lowest point is between the ends
        Probe lo = end_a, hi = end_b;
        for (int k = 0; k < 40 && hi.t - lo.t > 1e-9; ++k) {
            double t = (hi.f - lo.f + lo.slope * lo.t - hi.slope * hi.t) / (lo.slope - hi.slope);
            const double bound = lo.f + lo.slope * (t - lo.t); // f >= bound over [lo.t, hi.t]
            out.lower = bound;
            if (bound >= margin) return false;
            if (lowest.f - bound <= tolerance) break;
            // A cut hugging one end narrows slowly (a rounded distance's bottom): halve instead.
            const double width = hi.t - lo.t;
            if (t - lo.t < 0.05 * width || hi.t - t < 0.05 * width) t = 0.5 * (lo.t + hi.t);
            const Probe at = probe(shape, a, b, t);
            if (at.f < lowest.f) lowest = at;
            (at.slope < 0.0 ? lo : hi) = at;
            if (at.slope == 0.0) break;
        }
    }
    if (!(lowest.f < margin)) return false;
    auto crossing = [&](Probe p) { // from an end outside the margin towards the lowest point
        for (int k = 0; k < 30 && p.f - margin > tolerance && p.slope != 0.0; ++k) {
            const double t = std::clamp(p.t - (p.f - margin) / p.slope, std::min(p.t, lowest.t), std::max(p.t, lowest.t));
            if (t == p.t) break;
            p = probe(shape, a, b, t);
        }
        return p.t;
    };
    out.t = lowest.t;
    out.share = crossing(end_b) - crossing(end_a);
    return true;
}

/// A ball (its distance |x - c| - R): the nearest point of the edge to the centre, and where the
/// edge crosses the sphere of radius R + margin, in closed form (convex_reach's answer, exact).
bool ball_reach(const PlacedShape& ball, const Eigen::Vector3d& a, const Eigen::Vector3d& b, double margin, EdgeReach& out) noexcept
{
    const Eigen::Vector3d c = ball.position, e = b - a, ac = a - c;
    const double radius = -ball.signed_distance(c), ee = e.squaredNorm();
    const double t = ee > 0.0 ? std::clamp(-ac.dot(e) / ee, 0.0, 1.0) : 0.0;
    out.lower = (ac + t * e).norm() - radius;
    if (!(out.lower < margin)) return false;
    out.t = t;
    // |ac + s e|^2 = (R + margin)^2: a quadratic in s with a root on each side of t.
    const double r = radius + margin, half_b = ac.dot(e), disc = std::max(0.0, half_b * half_b - ee * (ac.squaredNorm() - r * r));
    const double root = std::sqrt(disc);
    out.share = ee > 0.0 ? std::clamp((-half_b + root) / ee, 0.0, 1.0) - std::clamp((-half_b - root) / ee, 0.0, 1.0) : 0.0;
    return true;
}

/// Where an edge reaches into a convex tool: in closed form for a ball, else by cutting planes.
bool convex_edge_reach(const PlacedShape& shape, const Eigen::Vector3d& a, const Eigen::Vector3d& b, double margin, EdgeReach& out) noexcept
{
    return shape.shape->kind() == ToolShape::Kind::sphere ? ball_reach(shape, a, b, margin, out) : convex_reach(shape, a, b, margin, out);
}

/// Any shape (a mesh tool's distance need not be convex): halving the edge while the distance's
/// Lipschitz bound leaves room, then a golden-section search for the deepest point and bisections
/// for where the edge leaves the margin on each side.
bool general_reach(const PlacedShape& shape, const Eigen::Vector3d& a, const Eigen::Vector3d& b, double f_a, double f_b, double margin,
                   EdgeReach& out) noexcept
{
    const double length = (b - a).norm();
    struct Span {
        double t0, t1, f0, f1;
    };
    std::array<Span, 24> stack{};
    int top = 0;
    stack[top++] = {0.0, 1.0, f_a, f_b};
    bool in = false;
    while (top > 0 && !in) {
        const Span s = stack[--top];
        if (0.5 * (s.f0 + s.f1 - (s.t1 - s.t0) * length) >= margin) continue; // 1-Lipschitz: this span stays out
        const double mid = 0.5 * (s.t0 + s.t1), fm = shape.signed_distance(a + mid * (b - a));
        in = fm < margin;
        if (top + 2 > static_cast<int>(stack.size()) || (s.t1 - s.t0) * length < 1e-4) continue; // finer than 0.1 um: out
        stack[top++] = {s.t0, mid, s.f0, fm};
        stack[top++] = {mid, s.t1, fm, s.f1};
    }
    if (!in) return false;
    auto distance = [&](double t) { return shape.signed_distance(a + t * (b - a)); };
    constexpr double golden = 0.6180339887498949;
    double lo = 0.0, hi = 1.0, t1 = hi - golden * (hi - lo), t2 = lo + golden * (hi - lo), f1 = distance(t1), f2 = distance(t2);
    for (int k = 0; k < 30 && (hi - lo) * length > 1e-4; ++k) {
        if (f1 < f2) {
            hi = t2, t2 = t1, f2 = f1, t1 = hi - golden * (hi - lo), f1 = distance(t1);
        } else {
            lo = t1, t1 = t2, f1 = f2, t2 = lo + golden * (hi - lo), f2 = distance(t2);
        }
    }
    out.t = 0.5 * (lo + hi);
    auto leaves = [&](double inside, double outside) {
        for (int k = 0; k < 30 && std::abs(outside - inside) * length > 1e-4; ++k) {
            const double mid = 0.5 * (inside + outside);
            (distance(mid) < margin ? inside : outside) = mid;
        }
        return 0.5 * (inside + outside);
    };
    out.share = distance(out.t) < margin ? leaves(out.t, 1.0) - leaves(out.t, 0.0) : 0.0;
    return true;
}

bool edge_penalty(const PlacedShape& tool, const PlacedShape* from, const ContactParameters& parameters, const Eigen::Vector3d& a,
                  const Eigen::Vector3d& b, double d_a, double d_b, double area_a, double area_b, const Eigen::Vector3d& n_a,
                  const Eigen::Vector3d& n_b, EdgePenalty& out) noexcept
{
    const double margin = parameters.margin_mm, length = (b - a).norm();
    if (!(d_a >= margin && d_b >= margin)) return false; // a point contact has it
    // 1-Lipschitz: the edge cannot reach in at a pose where its ends are this far out.
    auto out_of_reach = [&](double f0, double f1) { return 0.5 * (f0 + f1 - length) >= margin; };
    const double from_a = from ? from->signed_distance(a) : INFINITY, from_b = from ? from->signed_distance(b) : INFINITY;
    if (from_a < margin || from_b < margin) return false; // a point contact has it, at the step's start
    if (out_of_reach(d_a, d_b) && out_of_reach(from_a, from_b)) return false;

    // Where the edge reaches deepest, and the share of it inside, at the pose it reaches in at
    // (the end's, if both).
    const bool convex = tool.shape && tool.shape->kind() != ToolShape::Kind::mesh;
    EdgeReach reach;
    const bool in_now = convex ? convex_edge_reach(tool, a, b, margin, reach) : general_reach(tool, a, b, d_a, d_b, margin, reach);
    if (!in_now && !(from && (convex ? convex_edge_reach(*from, a, b, margin, reach) : general_reach(*from, a, b, from_a, from_b, margin, reach))))
        return false;
    const double t = reach.t;
    out.at = a + t * (b - a);
    out.distance = tool.signed_distance(out.at, &out.normal);
    out.depth = margin - out.distance;
    double inside = out.depth > 0.0 ? 1.0 : 0.0;
    if (from) out.depth = mean_penetration(margin - from->signed_distance(out.at), out.depth, inside);
    if (!(out.depth > 0.0)) return false;
    out.w_a = 1.0 - t;
    out.area = std::max(reach.share, 1e-3) * (area_a + area_b) / 6.0;
    const Eigen::Vector3d outward = out.w_a * n_a + t * n_b;
    if (outward.squaredNorm() > 0.0) out.normal = -outward.normalized(); // along the object's normal, as a point's
    const double k = parameters.stiffness_n_per_mm / 100.0 * out.area;
    out.force = k * out.depth * out.normal;
    out.stiffness = k * inside;
    return true;
}

/// How far the tool may move from where it is before the edge a-b can be pressed (ends at
/// distances d_a, d_b): while an end is inside the pushing shape the point contact has it, and an
/// edge that stays out is out by a lower bound of the distance along it; 0 if it is pressed now.
double edge_slack(const PlacedShape& tool, double margin, const Eigen::Vector3d& a, const Eigen::Vector3d& b, double d_a, double d_b) noexcept
{
    if (d_a < margin || d_b < margin) return std::max(d_a < margin ? margin - d_a : 0.0, d_b < margin ? margin - d_b : 0.0);
    double lower = 0.5 * (d_a + d_b - (b - a).norm()); // 1-Lipschitz
    EdgeReach reach;
    if (tool.shape->kind() != ToolShape::Kind::mesh) {
        if (convex_edge_reach(tool, a, b, margin, reach)) return 0.0;
        lower = std::max(lower, reach.lower);
    } else if (lower < margin && general_reach(tool, a, b, d_a, d_b, margin, reach)) {
        return 0.0;
    }
    return std::max(0.0, lower - margin);
}

/// Whether a point force carries the load: within 60 degrees of the net force on the object (all
/// of them when the forces cancel, a squeeze with no net push).
bool carries_load(const Eigen::Vector3d& force, const Eigen::Vector3d& net) noexcept
{
    return net.norm() <= 1e-12 || force.dot(net) >= 0.5 * force.norm() * net.norm();
}

/// The load-carrying area, at most the pushing shape's shadow across the net force: a blade
/// narrower than the surface's sampling, lying between two rows of points that both carry it,
/// would otherwise spread its force over both rows' area and press at half what it does.
double within_shadow(const PlacedShape& tool, double margin, const Eigen::Vector3d& net, double load_area) noexcept
{
    if (!(net.norm() > 1e-12) || !tool.shape) return load_area;
    return std::min(load_area, tool.shape->shadow_area(tool.orientation.conjugate() * net, margin));
}

} // namespace

double mean_penetration(double d0, double d1, double& inside) noexcept
{
    if (d0 >= 0.0 && d1 >= 0.0) { // inside throughout
        inside = 1.0;
        return 0.5 * (d0 + d1);
    }
    if (d0 <= 0.0 && d1 <= 0.0) { // outside throughout
        inside = 0.0;
        return 0.0;
    }
    const double deeper = std::max(d0, d1), span = std::abs(d1 - d0);
    inside = deeper / span;
    return 0.5 * deeper * inside;
}

ContactResult penalty_contact(const PlacedShape& tool, const ContactParameters& parameters,
                              std::span<const Eigen::Vector3d> points, std::span<const double> areas,
                              std::span<const Eigen::Vector3d> normals, const PlacedShape* from,
                              std::span<const Eigen::Vector3i> triangles)
{
    ContactResult out;
    Eigen::AlignedBox3d reach = tool.world_bounds(parameters.margin_mm);
    if (from) reach.extend(from->world_bounds(parameters.margin_mm));
    PointPenalty pp;
    std::vector<double> distance(triangles.empty() ? 0 : points.size(), std::numeric_limits<double>::quiet_NaN()); // NaN: not measured
    for (std::size_t i = 0; i < points.size(); ++i) {
        const bool inside = point_penalty(tool, from, parameters, reach, points[i], areas[i], normals[i], pp);
        if (!distance.empty() && pp.measured) distance[i] = pp.distance;
        if (!inside) continue;
        PointContact c;
        c.point = static_cast<std::uint32_t>(i);
        c.depth_mm = pp.depth;
        c.normal = pp.normal;
        c.stiffness_n_per_mm = pp.stiffness;
        c.force_n = pp.force;
        c.area_mm2 = areas[i];
        c.inside_inner = pp.distance < 0.0;
        out.force_on_tool_n -= c.force_n;
        out.torque_on_tool_n_mm -= (points[i] - tool.position).cross(c.force_n);
        out.area_mm2 += areas[i];
        out.points.push_back(c);
    }
    // Edges reaching in between their ends, their force shared by their ends as the point on them is.
    EdgePenalty ep;
    for (const Eigen::Vector2i& edge : surface_edges(triangles)) {
        const auto a = static_cast<std::size_t>(edge[0]), b = static_cast<std::size_t>(edge[1]);
        if (!reach.intersects(Eigen::AlignedBox3d(points[a].cwiseMin(points[b]), points[a].cwiseMax(points[b])))) continue;
        for (const std::size_t end : {a, b})
            if (std::isnan(distance[end])) distance[end] = tool.signed_distance(points[end]);
        if (!edge_penalty(tool, from, parameters, points[a], points[b], distance[a], distance[b], areas[a], areas[b], normals[a],
                          normals[b], ep))
            continue;
        for (const auto& [end, w] : {std::pair{a, ep.w_a}, std::pair{b, 1.0 - ep.w_a}}) {
            PointContact c;
            c.point = static_cast<std::uint32_t>(end);
            c.depth_mm = ep.depth;
            c.normal = ep.normal;
            c.stiffness_n_per_mm = w * ep.stiffness;
            c.force_n = w * ep.force;
            c.area_mm2 = w * ep.area;
            c.inside_inner = ep.distance < 0.0;
            out.points.push_back(c);
        }
        out.force_on_tool_n -= ep.force;
        out.torque_on_tool_n_mm -= (ep.at - tool.position).cross(ep.force);
        out.area_mm2 += ep.area;
    }
    const Eigen::Vector3d net = -out.force_on_tool_n;
    double magnitude = 0.0;
    for (const PointContact& c : out.points) {
        if (!carries_load(c.force_n, net)) continue;
        magnitude += c.force_n.norm();
        out.load_area_mm2 += c.area_mm2;
    }
    out.load_area_mm2 = within_shadow(tool, parameters.margin_mm, net, out.load_area_mm2);
    // N / mm^2 = 1e6 Pa.
    out.pressure_pa = out.load_area_mm2 > 0.0 ? 1e6 * magnitude / out.load_area_mm2 : 0.0;
    return out;
}

namespace {

/// The edges' pass of penalty_totals (both of its passes): calls visit(ep) for each edge that is
/// pressed, its ends' distances read from `distance` where measured (kept), else measured here.
template <class Visit>
void for_each_pressed_edge(const PlacedShape& tool, const ContactParameters& parameters, const SurfacePoints& points, const Eigen::AlignedBox3d& reach,
                           double spent, std::span<double> distance, Visit&& visit) noexcept
{
    const bool keep = distance.size() >= points.count;
    const bool own = points.stiffness_n_per_mm.size() >= points.count;
    ContactParameters at = parameters;
    auto edge_parameters = [&](std::size_t a, std::size_t b) -> const ContactParameters& {
        if (own) at.stiffness_n_per_mm = 0.5 * (points.stiffness_n_per_mm[a] + points.stiffness_n_per_mm[b]);
        return at;
    };
    // An end outside the pushing shape's box is measured here (and kept for the continuous check).
    auto measured = [&](std::size_t i) {
        if (keep && distance[i] < INFINITY) return distance[i];
        const double d = tool.signed_distance(points.positions_mm[i]);
        if (keep) distance[i] = d;
        return d;
    };
    // Cheap tests first (the loop visits every edge of the snapshot each tick): with both ends
    // measured, an end inside (its point contact has it) or the Lipschitz bound; else the box.
    auto may_reach_in = [&](std::size_t a, std::size_t b) {
        const Eigen::Vector3d &p = points.positions_mm[a], &q = points.positions_mm[b];
        if (keep && distance[a] < INFINITY && distance[b] < INFINITY) {
            const double margin = parameters.margin_mm, room = distance[a] + distance[b] - 2.0 * margin;
            return distance[a] >= margin && distance[b] >= margin && room * room < (q - p).squaredNorm();
        }
        return reach.intersects(Eigen::AlignedBox3d(p.cwiseMin(q), p.cwiseMax(q)));
    };
    EdgePenalty ep;
    points.for_each_edge_near(reach, [&](const Eigen::Vector2i& edge) {
        const auto a = static_cast<std::size_t>(edge[0]), b = static_cast<std::size_t>(edge[1]);
        if (b >= points.count || points.is_replaced(a) || points.is_replaced(b) || !may_reach_in(a, b)) return;
        const double d_a = measured(a), d_b = measured(b);
        if (edge_penalty(tool, nullptr, edge_parameters(a, b), points.positions_mm[a], points.positions_mm[b], d_a, d_b, points.areas_mm2[a],
                         points.areas_mm2[b], points.normals[a], points.normals[b], ep))
            visit(ep);
    }, spent);
}

void add_edge(const PlacedShape& tool, const EdgePenalty& e, ContactTotals& out)
{
    out.force_on_tool_n -= e.force;
    out.torque_on_tool_n_mm -= (e.at - tool.position).cross(e.force);
    out.stiffness_n_per_mm += e.stiffness * e.normal * e.normal.transpose();
    out.area_mm2 += e.area;
    out.inner_reaches_surface = out.inner_reaches_surface || e.distance < 0.0;
}

} // namespace

ContactTotals penalty_totals(const PlacedShape& tool, const ContactParameters& parameters, const SurfacePoints& points,
                             bool with_pressure, std::span<double> distance) noexcept
{
    ContactTotals out;
    const Eigen::AlignedBox3d reach = tool.world_bounds(parameters.margin_mm);
    const bool keep = distance.size() >= points.count;
    if (keep) std::fill(distance.begin(), distance.begin() + static_cast<std::ptrdiff_t>(points.count), std::numeric_limits<double>::infinity());
    PointPenalty pp;
    // Each point's parameters: the tool's, or the stiffness the snapshot gives it.
    const bool own = points.stiffness_n_per_mm.size() >= points.count;
    ContactParameters at = parameters;
    auto parameters_of = [&](std::size_t i) -> const ContactParameters& {
        if (own) at.stiffness_n_per_mm = points.stiffness_n_per_mm[i];
        return at;
    };
    // Only the points and edges near the tool are visited (the snapshot's grid), and of those only
    // the ones whose slack the tool has used up since the snapshot was measured; the others keep
    // +infinity.
    const double spent = points.slack_spent(tool, parameters.margin_mm);
    points.for_each_point_near(reach, [&](std::size_t i) {
        if (points.is_replaced(i)) return; // the contact patch has it
        const Eigen::Vector3d& p = points.positions_mm[i];
        const bool inside = point_penalty(tool, nullptr, parameters_of(i), reach, p, points.areas_mm2[i], points.normals[i], pp);
        if (keep && pp.measured) distance[i] = pp.distance;
        if (!inside) return;
        out.force_on_tool_n -= pp.force;
        out.torque_on_tool_n_mm -= (p - tool.position).cross(pp.force);
        out.stiffness_n_per_mm += pp.stiffness * pp.normal * pp.normal.transpose();
        out.area_mm2 += points.areas_mm2[i];
        out.inner_reaches_surface = out.inner_reaches_surface || pp.distance < 0.0;
    }, spent);
    // The edges, as penalty_contact takes them (their ends' distances from the pass above when
    // kept, else measured again).
    for_each_pressed_edge(tool, parameters, points, reach, spent, distance, [&](const EdgePenalty& e) { add_edge(tool, e, out); });
    if (!with_pressure || out.area_mm2 == 0.0) return out;
    // A second pass for the load-carrying part: nothing is stored per point.
    const Eigen::Vector3d net = -out.force_on_tool_n;
    double magnitude = 0.0;
    points.for_each_point_near(reach, [&](std::size_t i) {
        if (points.is_replaced(i)) return;
        if (!point_penalty(tool, nullptr, parameters_of(i), reach, points.positions_mm[i], points.areas_mm2[i], points.normals[i], pp))
            return;
        if (!carries_load(pp.force, net)) return;
        magnitude += pp.force.norm();
        out.load_area_mm2 += points.areas_mm2[i];
    }, spent);
    for_each_pressed_edge(tool, parameters, points, reach, spent, distance, [&](const EdgePenalty& e) {
        if (!carries_load(e.force, net)) return;
        magnitude += e.force.norm();
        out.load_area_mm2 += e.area;
    });
    out.load_area_mm2 = within_shadow(tool, parameters.margin_mm, net, out.load_area_mm2);
    out.pressure_pa = out.load_area_mm2 > 0.0 ? 1e6 * magnitude / out.load_area_mm2 : 0.0;
    return out;
}

void add_edge_totals(const PlacedShape& tool, const ContactParameters& parameters, const SurfacePoints& points, std::span<double> distance,
                     ContactTotals& out) noexcept
{
    for_each_pressed_edge(tool, parameters, points, tool.world_bounds(parameters.margin_mm), points.slack_spent(tool, parameters.margin_mm), distance,
                          [&](const EdgePenalty& e) { add_edge(tool, e, out); });
}

void measure_slack(const PlacedShape& tool, double margin_mm, SurfacePoints& points)
{
    // Stored a hair short, in float: a slack is only ever an underestimate.
    auto stored = [](double slack) { return static_cast<float>(std::max(0.0, slack - 1e-5)); };
    std::vector<double> distance(points.count);
    points.slack_radius_mm = 0.0;
    for (std::size_t i = 0; i < points.count; ++i) {
        distance[i] = tool.signed_distance(points.positions_mm[i]);
        points.slack_radius_mm = std::max(points.slack_radius_mm, (points.positions_mm[i] - tool.position).norm());
    }
    PointGrid& grid = points.grid;
    grid.point_slack.resize(points.count);
    for (std::size_t k = 0; k < points.count; ++k) grid.point_slack[k] = stored(distance[k] - margin_mm);
    grid.edge_slack.resize(grid.edges.size());
    for (std::size_t k = 0; k < grid.edges.size(); ++k) {
        const auto a = static_cast<std::size_t>(grid.edges[k].ends[0]), b = static_cast<std::size_t>(grid.edges[k].ends[1]);
        grid.edge_slack[k] =
            b < points.count ? stored(edge_slack(tool, margin_mm, points.positions_mm[a], points.positions_mm[b], distance[a], distance[b])) : 0.0f;
    }
    points.slack_pose = tool;
    points.slack_margin_mm = margin_mm;
}

} // namespace vox::contact
