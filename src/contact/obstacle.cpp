#include "contact/obstacle.hpp"

#include "core/error.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

namespace vox::contact {

Obstacle Obstacle::plane(const Eigen::Vector3d& point_mm, const Eigen::Vector3d& normal)
{
    Obstacle o;
    o.m_origin = point_mm;
    o.m_normal = normal.normalized();
    return o;
}

Obstacle Obstacle::box(const Eigen::Vector3d& lo, const Eigen::Vector3d& hi)
{
    Obstacle o;
    o.m_shape = ToolShape::box(hi - lo);
    o.m_origin = 0.5 * (lo + hi);
    o.m_bounds = Eigen::AlignedBox3d(lo, hi);
    return o;
}

Obstacle Obstacle::mesh(TriangleMesh world_mesh)
{
    if (world_mesh.triangles.empty()) throw InputError("obstacle mesh: it has no triangle");
    Obstacle o;
    o.m_bounds.setEmpty();
    for (const Eigen::Vector3d& p : world_mesh.positions) o.m_bounds.extend(p);
    o.m_shape = ToolShape::from_mesh(std::move(world_mesh));
    return o;
}

double Obstacle::signed_distance(const Eigen::Vector3d& p, Eigen::Vector3d* gradient) const noexcept
{
    if (!m_shape) {
        if (gradient) *gradient = m_normal;
        return (p - m_origin).dot(m_normal);
    }
    return m_shape->signed_distance(m_shape->kind() == ToolShape::Kind::box ? Eigen::Vector3d(p - m_origin) : p, gradient);
}

bool Obstacle::may_reach(const Eigen::AlignedBox3d& box) const
{
    if (box.isEmpty()) return false;
    if (m_shape) return box.intersects(m_bounds);
    // The box's corner farthest along -normal is its deepest point.
    Eigen::Vector3d deepest;
    for (int a = 0; a < 3; ++a) deepest[a] = m_normal[a] > 0.0 ? box.min()[a] : box.max()[a];
    return (deepest - m_origin).dot(m_normal) < 0.0;
}

Eigen::AlignedBox3d Obstacle::bounds() const
{
    if (m_shape) return m_bounds;
    const double far = std::numeric_limits<double>::max();
    return {Eigen::Vector3d::Constant(-far), Eigen::Vector3d::Constant(far)};
}

TriangleMesh Obstacle::drawing_mesh(const Eigen::Vector3d& centre_mm, double extent_mm) const
{
    if (m_shape) {
        TriangleMesh m = m_shape->mesh();
        if (m_shape->kind() == ToolShape::Kind::box)
            for (Eigen::Vector3d& p : m.positions) p += m_origin;
        return m;
    }
    const Eigen::Vector3d foot = centre_mm - (centre_mm - m_origin).dot(m_normal) * m_normal;
    const Eigen::Vector3d u = m_normal.unitOrthogonal(), v = m_normal.cross(u);
    TriangleMesh m;
    for (const double su : {-1.0, 1.0})
        for (const double sv : {-1.0, 1.0}) m.positions.push_back(foot + extent_mm * (su * u + sv * v));
    m.triangles = {{0, 1, 3}, {0, 3, 2}}; // (u x v) = normal: counter-clockwise seen from the free side
    return m;
}

ContactResult obstacle_contact(const Obstacle& obstacle, std::span<const Eigen::Vector3d> points, std::span<const double> areas,
                               std::span<const Eigen::Vector3d> velocities_mm_s, double dt_s, std::span<const std::uint64_t> keys,
                               FrictionAnchors& anchors, double skin_mm, std::span<const Eigen::Vector3d> ends_mm)
{
    ContactResult out;
    FrictionAnchors held;
    Eigen::Vector3d total = Eigen::Vector3d::Zero();
    for (std::size_t i = 0; i < points.size(); ++i) {
        Eigen::Vector3d g;
        const double depth = -obstacle.signed_distance(points[i], &g);
        // Touching, or arriving within the step (inside where the step would take it freely).
        const bool arriving = depth > -skin_mm || (!ends_mm.empty() && obstacle.signed_distance(ends_mm[i]) < 0.0);
        if (!(depth > 0.0) && !arriving) continue;
        const double k = obstacle.stiffness_n_per_mm / 100.0 * areas[i]; // per mm^2 of contact
        PointContact c;
        c.point = static_cast<std::uint32_t>(i);
        c.depth_mm = depth;
        c.normal = g;
        c.stiffness_n_per_mm = k;
        c.force_n = k * depth * g; // apart: pulls, until the step's end says whether it pushes
        if (depth > 0.0) {
            out.area_mm2 += areas[i];
            // Friction: the spring to the anchor, across the normal, slipping beyond mu |f_n|.
            const auto found = anchors.find(keys[i]);
            Eigen::Vector3d anchor = found == anchors.end() ? points[i] : found->second;
            const Eigen::Matrix3d across = Eigen::Matrix3d::Identity() - g * g.transpose();
            const Eigen::Vector3d stretch = across * (points[i] - anchor);
            const double limit = obstacle.friction * k * depth; // mu |f_n|
            // The spring reaches the limit over the larger of k_stick_give_mm and the step's expected
            // slide: within one step it cannot pull much beyond mu |f_n|.
            const double slide = (across * velocities_mm_s[i]).norm() * dt_s;
            const double spring = std::min(k, limit / std::max(k_stick_give_mm, slide));
            const double pull = spring * stretch.norm();
            if (pull <= limit) {
                c.force_n -= spring * stretch;
                c.friction_stiffness_n_per_mm = spring * across;
            } else { // slips: the anchor follows at the distance where the spring pulls with mu |f_n|
                const Eigen::Vector3d way = stretch / stretch.norm();
                anchor = points[i] - (limit / spring) * way;
                c.force_n -= limit * way;
                c.friction_stiffness_n_per_mm = spring * (across - way * way.transpose());
            }
            held.emplace(keys[i], anchor);
            total += c.force_n;
        }
        out.points.push_back(c);
    }
    anchors = std::move(held);
    out.force_on_tool_n = -total;
    out.load_area_mm2 = out.area_mm2;
    if (out.area_mm2 > 0.0) out.pressure_pa = total.norm() / out.area_mm2 * 1e6;
    return out;
}

} // namespace vox::contact
