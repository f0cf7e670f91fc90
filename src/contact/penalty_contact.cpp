#include "contact/penalty_contact.hpp"

#include <algorithm>
#include <limits>
#include <cmath>

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

/// Whether a point force carries the load: within 60 degrees of the net force on the object (all
/// of them when the forces cancel, a squeeze with no net push).
bool carries_load(const Eigen::Vector3d& force, const Eigen::Vector3d& net) noexcept
{
    return net.norm() <= 1e-12 || force.dot(net) >= 0.5 * force.norm() * net.norm();
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
                              std::span<const Eigen::Vector3d> normals, const PlacedShape* from)
{
    ContactResult out;
    Eigen::AlignedBox3d reach = tool.world_bounds(parameters.margin_mm);
    if (from) reach.extend(from->world_bounds(parameters.margin_mm));
    PointPenalty pp;
    for (std::size_t i = 0; i < points.size(); ++i) {
        if (!point_penalty(tool, from, parameters, reach, points[i], areas[i], normals[i], pp)) continue;
        PointContact c;
        c.point = static_cast<std::uint32_t>(i);
        c.depth_mm = pp.depth;
        c.normal = pp.normal;
        c.stiffness_n_per_mm = pp.stiffness;
        c.force_n = pp.force;
        c.inside_inner = pp.distance < 0.0;
        out.force_on_tool_n -= c.force_n;
        out.torque_on_tool_n_mm -= (points[i] - tool.position).cross(c.force_n);
        out.area_mm2 += areas[i];
        out.points.push_back(c);
    }
    const Eigen::Vector3d net = -out.force_on_tool_n;
    double magnitude = 0.0;
    for (const PointContact& c : out.points) {
        if (!carries_load(c.force_n, net)) continue;
        magnitude += c.force_n.norm();
        out.load_area_mm2 += areas[c.point];
    }
    // N / mm^2 = 1e6 Pa.
    out.pressure_pa = out.load_area_mm2 > 0.0 ? 1e6 * magnitude / out.load_area_mm2 : 0.0;
    return out;
}

ContactTotals penalty_totals(const PlacedShape& tool, const ContactParameters& parameters, const SurfacePoints& points,
                             bool with_pressure, std::span<double> distance) noexcept
{
    ContactTotals out;
    const Eigen::AlignedBox3d reach = tool.world_bounds(parameters.margin_mm);
    const bool keep = distance.size() >= points.count;
    PointPenalty pp;
    for (std::size_t i = 0; i < points.count; ++i) {
        const Eigen::Vector3d& p = points.positions_mm[i];
        const bool inside = point_penalty(tool, nullptr, parameters, reach, p, points.areas_mm2[i], points.normals[i], pp);
        if (keep) distance[i] = pp.measured ? pp.distance : std::numeric_limits<double>::infinity();
        if (!inside) continue;
        out.force_on_tool_n -= pp.force;
        out.torque_on_tool_n_mm -= (p - tool.position).cross(pp.force);
        out.stiffness_n_per_mm += pp.stiffness * pp.normal * pp.normal.transpose();
        out.area_mm2 += points.areas_mm2[i];
        out.inner_reaches_surface = out.inner_reaches_surface || pp.distance < 0.0;
    }
    if (!with_pressure || out.area_mm2 == 0.0) return out;
    // A second pass for the load-carrying part: nothing is stored per point.
    const Eigen::Vector3d net = -out.force_on_tool_n;
    double magnitude = 0.0;
    for (std::size_t i = 0; i < points.count; ++i) {
        if (!point_penalty(tool, nullptr, parameters, reach, points.positions_mm[i], points.areas_mm2[i], points.normals[i], pp)) continue;
        if (!carries_load(pp.force, net)) continue;
        magnitude += pp.force.norm();
        out.load_area_mm2 += points.areas_mm2[i];
    }
    out.pressure_pa = out.load_area_mm2 > 0.0 ? 1e6 * magnitude / out.load_area_mm2 : 0.0;
    return out;
}

} // namespace vox::contact
