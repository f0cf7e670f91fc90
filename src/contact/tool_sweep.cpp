#include "contact/tool_sweep.hpp"

#include "contact/ccd.hpp"
#include "contact/swept_contact.hpp"

#include <algorithm>
#include <limits>

namespace vox::contact {

ToolSweep::ToolSweep(const ToolShape& shape, double margin_mm, std::size_t point_capacity)
    : m_margin(margin_mm), m_local(shape.mesh(0.0, 1)), m_start(m_local.positions.size()), m_end(m_local.positions.size()),
      m_clearance(point_capacity)
{
    for (const Eigen::Vector3i& f : m_local.triangles)
        for (int c = 0; c < 3; ++c) {
            const int a = std::min(f[c], f[(c + 1) % 3]), b = std::max(f[c], f[(c + 1) % 3]);
            if (std::find(m_edges.begin(), m_edges.end(), std::array<int, 2>{a, b}) == m_edges.end()) m_edges.push_back({a, b});
        }
}

bool ToolSweep::reachable(const Eigen::Vector3i& triangle, const PlacedShape& from, const SurfacePoints& points, double speed) noexcept
{
    // A triangle with a corner in the contact is the penalty's. One farther from the tool than the
    // move plus its own size cannot be reached: the distance is 1-Lipschitz, and a corner's
    // distance to the tool is its clearance (to the pushing shape) plus the margin.
    constexpr double far = std::numeric_limits<double>::infinity();
    double nearest = far, size = 0.0;
    for (int c = 0; c < 3; ++c) {
        const auto v = static_cast<std::size_t>(triangle[c]);
        double& clearance = m_clearance[v];
        if (clearance == far) clearance = from.signed_distance(points.positions_mm[v]) - m_margin; // outside the swept box: measured now
        nearest = std::min(nearest, clearance);
        size = std::max(size, (points.positions_mm[v] - points.positions_mm[static_cast<std::size_t>(triangle[(c + 1) % 3])]).norm());
    }
    return nearest != -far && nearest + m_margin <= speed + size;
}

double ToolSweep::first_stop(const PlacedShape& from, const PlacedShape& to, const SurfacePoints& points) noexcept
{
    m_swept_mesh = m_stopped_by_mesh = false;
    const std::size_t n = std::min(points.count, m_clearance.size());
    double first = first_missed_contact(from, to, m_margin, points, std::span<double>(m_clearance.data(), n));
    if (points.triangles.empty() || n < points.count) return first;
    double speed = 0.0; // largest distance a tool vertex moves over the tick, mm
    for (std::size_t v = 0; v < m_local.positions.size(); ++v) {
        m_start[v] = from.position + from.orientation * m_local.positions[v];
        m_end[v] = to.position + to.orientation * m_local.positions[v];
        speed = std::max(speed, (m_end[v] - m_start[v]).norm());
    }
    // Only a move longer than the margin can carry a thin tool through a thin wall between its
    // points (a jump: the proxy catching up with a fast hand). Slower, the tool's edge entering a
    // face between points is the point contact's approximation, and cutting relies on it: the
    // blade must reach the points it then cuts.
    if (!(speed > m_margin)) return first;
    m_swept_mesh = true;
    // Surface points the tool's mesh meets are inside the pushing shape then (the inner shape lies
    // within it), so the point test has them already: only tool corners against surface faces and
    // tool edges against surface edges remain. The surface does not move over a tick, and a tool
    // corner's height over a surface plane is linear in t: corners strictly on one side at both
    // ends stay there throughout (a cheap first pass before the exact tests, as are the boxes).
    const auto& p = points.positions_mm;
    using Points = std::array<Eigen::Vector3d, 4>;
    double toi = std::numeric_limits<double>::infinity();
    auto side = [&](const Eigen::Vector3d& normal, const Eigen::Vector3d& origin, std::size_t v) {
        const double tolerance = 1e-9 * normal.norm(), h0 = normal.dot(m_start[v] - origin), h1 = normal.dot(m_end[v] - origin);
        return h0 > tolerance && h1 > tolerance ? 1 : h0 < -tolerance && h1 < -tolerance ? -1 : 0;
    };
    for (std::size_t v = 0; v < m_start.size(); ++v) {
        const Eigen::AlignedBox3d sweep = Eigen::AlignedBox3d(m_start[v]).extend(m_end[v]);
        points.triangle_tree.query(sweep.min(), sweep.max(), [&](std::uint32_t t) {
            const Eigen::Vector3i& f = points.triangles[t];
            const Eigen::Vector3d &a = p[static_cast<std::size_t>(f[0])], &b = p[static_cast<std::size_t>(f[1])], &c = p[static_cast<std::size_t>(f[2])];
            if (!reachable(f, from, points, speed) || side((b - a).cross(c - a), a, v) != 0) return;
            toi = std::min(toi, vertex_face_toi(Points{m_start[v], a, b, c}, Points{m_end[v], a, b, c}));
        });
    }
    for (const auto& [e0, e1] : m_edges) {
        const auto v0 = static_cast<std::size_t>(e0), v1 = static_cast<std::size_t>(e1);
        const Eigen::AlignedBox3d sweep = Eigen::AlignedBox3d(m_start[v0]).extend(m_end[v0]).extend(m_start[v1]).extend(m_end[v1]);
        points.triangle_tree.query(sweep.min(), sweep.max(), [&](std::uint32_t t) {
            const Eigen::Vector3i& f = points.triangles[t];
            const Eigen::Vector3d normal = (p[static_cast<std::size_t>(f[1])] - p[static_cast<std::size_t>(f[0])]).cross(p[static_cast<std::size_t>(f[2])] - p[static_cast<std::size_t>(f[0])]);
            const int s0 = side(normal, p[static_cast<std::size_t>(f[0])], v0);
            if ((s0 != 0 && s0 == side(normal, p[static_cast<std::size_t>(f[0])], v1)) || !reachable(f, from, points, speed)) return;
            for (int j = 0; j < 3; ++j) { // a surface edge shared by two triangles is tested from both
                const Eigen::Vector3d &a = p[static_cast<std::size_t>(f[j])], &b = p[static_cast<std::size_t>(f[(j + 1) % 3])];
                if (sweep.intersects(Eigen::AlignedBox3d(a).extend(b)))
                    toi = std::min(toi, edge_edge_toi(Points{m_start[v0], m_start[v1], a, b}, Points{m_end[v0], m_end[v1], a, b}));
            }
        });
    }
    if (toi <= 1.0) {
        const double stop = std::max(0.0, toi - 1e-3 / speed); // 1 um short of the contact
        if (stop < first) {
            first = stop;
            m_stopped_by_mesh = true;
        }
    }
    return first;
}

} // namespace vox::contact
