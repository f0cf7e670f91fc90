#include "contact/penalty_contact.hpp"

namespace vox::contact {

ContactResult penalty_contact(const PlacedShape& tool, const ContactParameters& parameters,
                              std::span<const Eigen::Vector3d> points, std::span<const double> areas,
                              std::span<const Eigen::Vector3d> normals)
{
    ContactResult out;
    const Eigen::AlignedBox3d reach = tool.world_bounds(parameters.margin_mm);
    const double per_mm3 = parameters.stiffness_n_per_mm / 100.0; // N per mm of depth per mm^2
    double magnitude = 0.0;
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
        magnitude += c.force_n.norm();
        out.points.push_back(c);
    }
    // N / mm^2 = 1e6 Pa.
    out.pressure_pa = out.area_mm2 > 0.0 ? 1e6 * magnitude / out.area_mm2 : 0.0;
    return out;
}

} // namespace vox::contact
