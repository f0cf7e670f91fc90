#include "contact/penalty_contact.hpp"

namespace vox::contact {

ContactResult penalty_contact(const PlacedShape& tool, const ContactParameters& parameters,
                              std::span<const Eigen::Vector3d> points, std::span<const double> areas,
                              std::span<const Eigen::Vector3d> normals)
{
    ContactResult out;
    const Eigen::AlignedBox3d reach = tool.world_bounds(parameters.margin_mm);
    const double per_mm3 = parameters.stiffness_n_per_mm / 100.0; // N per mm of depth per mm^2
    for (std::size_t i = 0; i < points.size(); ++i) {
        if (!reach.contains(points[i])) continue;
        Eigen::Vector3d normal;
        const double distance = tool.signed_distance(points[i], &normal);
        if (normals[i].squaredNorm() > 0.0) normal = -normals[i];
        const double depth = parameters.margin_mm - distance;
        if (!(depth > 0.0)) continue;
        PointContact c;
        c.point = static_cast<std::uint32_t>(i);
        c.depth_mm = depth;
        c.normal = normal;
        c.stiffness_n_per_mm = per_mm3 * areas[i];
        c.force_n = c.stiffness_n_per_mm * depth * normal;
        c.inside_inner = distance < 0.0;
        out.force_on_tool_n -= c.force_n;
        out.torque_on_tool_n_mm -= (points[i] - tool.position).cross(c.force_n);
        out.area_mm2 += areas[i];
        out.points.push_back(c);
    }
    // The load-carrying part: forces within 60 degrees of the net force on the object (all of
    // them when the forces cancel, a squeeze with no net push).
    const Eigen::Vector3d net = -out.force_on_tool_n;
    double magnitude = 0.0;
    for (const PointContact& c : out.points) {
        const double f = c.force_n.norm();
        if (c.force_n.dot(net) < 0.5 * f * net.norm() && net.norm() > 1e-12) continue;
        magnitude += f;
        out.load_area_mm2 += areas[c.point];
    }
    // N / mm^2 = 1e6 Pa.
    out.pressure_pa = out.load_area_mm2 > 0.0 ? 1e6 * magnitude / out.load_area_mm2 : 0.0;
    return out;
}

ContactTotals penalty_totals(const PlacedShape& tool, const ContactParameters& parameters, const SurfacePoints& points,
                             bool with_pressure) noexcept
{
    ContactTotals out;
    const Eigen::AlignedBox3d reach = tool.world_bounds(parameters.margin_mm);
    const double per_mm3 = parameters.stiffness_n_per_mm / 100.0; // N per mm of depth per mm^2
    for (std::size_t i = 0; i < points.count; ++i) {
        const Eigen::Vector3d& p = points.positions_mm[i];
        if (!reach.contains(p)) continue;
        Eigen::Vector3d normal;
        const double distance = tool.signed_distance(p, &normal);
        const double depth = parameters.margin_mm - distance;
        if (!(depth > 0.0)) continue;
        if (points.normals[i].squaredNorm() > 0.0) normal = -points.normals[i];
        const double k = per_mm3 * points.areas_mm2[i];
        const Eigen::Vector3d f = k * depth * normal;
        out.force_on_tool_n -= f;
        out.torque_on_tool_n_mm -= (p - tool.position).cross(f);
        out.stiffness_n_per_mm += k * normal * normal.transpose();
        out.area_mm2 += points.areas_mm2[i];
        out.inner_reaches_surface = out.inner_reaches_surface || distance < 0.0;
    }
    // A second pass for the load-carrying part (as penalty_contact): nothing is stored per point.
    const Eigen::Vector3d net = -out.force_on_tool_n;
    double magnitude = 0.0;
    for (std::size_t i = 0; with_pressure && i < points.count && out.area_mm2 > 0.0; ++i) {
        const Eigen::Vector3d& p = points.positions_mm[i];
        if (!reach.contains(p)) continue;
        Eigen::Vector3d normal;
        const double depth = parameters.margin_mm - tool.signed_distance(p, &normal);
        if (!(depth > 0.0)) continue;
        if (points.normals[i].squaredNorm() > 0.0) normal = -points.normals[i];
        const Eigen::Vector3d f = per_mm3 * points.areas_mm2[i] * depth * normal;
        if (f.dot(net) < 0.5 * f.norm() * net.norm() && net.norm() > 1e-12) continue;
        magnitude += f.norm();
        out.load_area_mm2 += points.areas_mm2[i];
    }
    out.pressure_pa = out.load_area_mm2 > 0.0 ? 1e6 * magnitude / out.load_area_mm2 : 0.0;
    return out;
}

} // namespace vox::contact
