#include "contact/tool_sweep.hpp"

#include "contact/ccd.hpp"
#include "contact/swept_contact.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

namespace vox::contact {

ToolSweep::ToolSweep(const ToolShape& shape, double margin_mm, std::size_t point_capacity)
    : m_margin(margin_mm), m_local(shape.mesh(0.0, 1)), m_start(m_local.positions.size()), m_end(m_local.positions.size()),
      m_clearance(point_capacity)
{
    // The mesh's edges, each once, leaving out those between two coplanar triangles (the
    // diagonals of a box's faces): a surface edge first meets a flat face at the face's border or
    // at one of its own ends (which the point test has), never first at such a diagonal.
    const auto& v = m_local.positions;
    auto normal = [&](const Eigen::Vector3i& f) { return Eigen::Vector3d((v[f[1]] - v[f[0]]).cross(v[f[2]] - v[f[0]]).normalized()); };
    for (std::size_t i = 0; i < m_local.triangles.size(); ++i) {
        const Eigen::Vector3i& f = m_local.triangles[i];
        for (int c = 0; c < 3; ++c) {
            const int a = std::min(f[c], f[(c + 1) % 3]), b = std::max(f[c], f[(c + 1) % 3]);
            if (std::find(m_edges.begin(), m_edges.end(), std::array<int, 2>{a, b}) != m_edges.end()) continue;
            bool flat = false; // shared with a coplanar triangle
            for (std::size_t j = 0; j < m_local.triangles.size() && !flat; ++j) {
                const Eigen::Vector3i& g = m_local.triangles[j];
                const bool shares = j != i && (g.array() == a).any() && (g.array() == b).any();
                flat = shares && normal(f).dot(normal(g)) > 1.0 - 1e-9;
            }
            if (!flat) m_edges.push_back({a, b});
        }
    }
}

bool ToolSweep::reachable(const Eigen::Vector3i& triangle, const PlacedShape& from, const SurfacePoints& points, double speed) noexcept
{
    // One farther from the tool than the move plus its own size cannot be reached: the distance
    // is 1-Lipschitz, and a corner's distance to the tool is its clearance (to the pushing shape)
    // plus the margin.
    constexpr double far = std::numeric_limits<double>::infinity();
    double nearest = far, size = 0.0;
    for (int c = 0; c < 3; ++c) {
        const auto v = static_cast<std::size_t>(triangle[c]);
        double& clearance = m_clearance[v];
        if (clearance == far) clearance = from.signed_distance(points.positions_mm[v]) - m_margin; // outside the swept box: measured now
        nearest = std::min(nearest, clearance);
        size = std::max(size, (points.positions_mm[v] - points.positions_mm[static_cast<std::size_t>(triangle[(c + 1) % 3])]).norm());
    }
    return nearest + m_margin <= speed + size;
}

double ToolSweep::first_stop(const PlacedShape& from, const PlacedShape& to, const SurfacePoints& points,
                             std::span<const double> from_distance) noexcept
{
    m_swept_mesh = m_stopped_by_mesh = false;
    const std::size_t n = std::min(points.count, m_clearance.size());
    double speed = 0.0; // largest distance a tool vertex moves over the tick, mm
    for (std::size_t v = 0; v < m_local.positions.size(); ++v) {
        m_start[v] = from.position + from.orientation * m_local.positions[v];
        m_end[v] = to.position + to.orientation * m_local.positions[v];
        speed = std::max(speed, (m_end[v] - m_start[v]).norm());
    }
    // Only a move longer than the margin can carry a thin tool through a thin wall between its
    // points (a jump: the proxy catching up with a fast hand). Slower, the tool's edge entering a
    // face between points is the point contact's approximation, and cutting relies on it: the
    // blade must reach the points it then cuts. The points' clearances are kept only for the mesh
    // test (most ticks have none).
    const bool mesh = !points.triangles.empty() && n == points.count && speed > m_margin;
    double first = first_missed_contact(from, to, m_margin, points, mesh ? std::span<double>(m_clearance.data(), n) : std::span<double>(),
                                        from_distance);
    if (!mesh) return first;
    m_swept_mesh = true;
    // Surface points the tool's mesh meets are inside the pushing shape then (the inner shape lies
    // within it), so the point test has them already: only tool corners against surface faces and
    // tool edges against surface edges remain. The surface does not move over a tick, so a tool
    // corner's height over a surface plane is linear in t, and the time it first reaches the
    // plane is a lower bound for its contact with the face, and for its edges' contacts with the
    // face's edges: pairs that cannot reach the plane, or only after the earliest contact found so
    // far, skip the exact test (a flat jab crosses many pairs at once; one exact search suffices).
    const auto& p = points.positions_mm;
    using Points = std::array<Eigen::Vector3d, 4>;
    double toi = std::numeric_limits<double>::infinity();
    // The exact tests halve the tick until a leaf is a quarter of the margin of travel (at least
    // 10 um): the first contact is found that closely, and then the pushing shell, not the mesh,
    // holds the tool; deeper halvings would cost more than the whole tick's budget.
    CcdOptions ccd;
    ccd.max_depth = std::clamp(static_cast<int>(std::ceil(std::log2(4.0 * speed / std::max(m_margin, 0.01)))), 4, 24);
    // The proxy's step moves the tool without turning it: every corner moves by the same vector,
    // and the exact tests take their closed-form root (ccd.hpp's translating queries).
    const bool translating = from.orientation.coeffs() == to.orientation.coeffs();
    const Eigen::Vector3d move = to.position - from.position;
    // Heights of tool corner v over the plane through `origin` with normal `normal`, at both ends.
    auto heights = [&](const Eigen::Vector3d& normal, const Eigen::Vector3d& origin, std::size_t v) {
        return std::pair{normal.dot(m_start[v] - origin), normal.dot(m_end[v] - origin)};
    };
    // Earliest t at which a segment whose ends' heights go linearly from (a0, a1) and (b0, b1)
    // meets the plane (a single corner: b = a); 2 when never. A rounding slack keeps it a bound.
    auto plane_entry = [](double a0, double a1, double b0, double b1, double tolerance) {
        if ((a0 <= tolerance && b0 >= -tolerance) || (a0 >= -tolerance && b0 <= tolerance)) return 0.0; // on or across it at the start
        double t = 2.0;
        for (const auto& [h0, h1] : {std::pair{a0, a1}, std::pair{b0, b1}})
            if ((h0 > 0.0) != (h1 > 0.0) || std::abs(h1) <= tolerance) t = std::min(t, std::max(0.0, h0 / (h0 - h1) - 1e-9));
        return t;
    };
    // A triangle with a corner in the contact at the start of the tick is the penalty's (the tool
    // is already against it), left out before anything is computed for it: a knife deep in its
    // cut lies against hundreds. So is one the contact patch stands in for (it gives way under the
    // tool, which then goes deeper than the snapshot's surface there).
    auto held = [&](const Eigen::Vector3i& f) {
        if (points.is_replaced(static_cast<std::size_t>(f[0])) || points.is_replaced(static_cast<std::size_t>(f[1])) ||
            points.is_replaced(static_cast<std::size_t>(f[2])))
            return true;
        return m_clearance[static_cast<std::size_t>(f[0])] == -INFINITY || m_clearance[static_cast<std::size_t>(f[1])] == -INFINITY ||
               m_clearance[static_cast<std::size_t>(f[2])] == -INFINITY;
    };
    for (std::size_t v = 0; v < m_start.size(); ++v) {
        const Eigen::AlignedBox3d sweep = Eigen::AlignedBox3d(m_start[v]).extend(m_end[v]);
        points.triangle_tree.query(sweep.min(), sweep.max(), [&](std::uint32_t t) {
            const Eigen::Vector3i& f = points.triangles[t];
            if (held(f)) return;
            const Eigen::Vector3d &a = p[static_cast<std::size_t>(f[0])], &b = p[static_cast<std::size_t>(f[1])], &c = p[static_cast<std::size_t>(f[2])];
            const Eigen::Vector3d normal = (b - a).cross(c - a);
            const auto [h0, h1] = heights(normal, a, v);
            if (plane_entry(h0, h1, h0, h1, 1e-9 * normal.norm()) >= std::min(toi, 1.0 + 1e-9) || !reachable(f, from, points, speed)) return;
            toi = std::min(toi, translating ? translating_vertex_face_toi(m_start[v], move, {a, b, c}, ccd, toi)
                                            : vertex_face_toi(Points{m_start[v], a, b, c}, Points{m_end[v], a, b, c}, ccd, toi));
        });
    }
    for (const auto& [e0, e1] : m_edges) {
        const auto v0 = static_cast<std::size_t>(e0), v1 = static_cast<std::size_t>(e1);
        const Eigen::AlignedBox3d sweep = Eigen::AlignedBox3d(m_start[v0]).extend(m_end[v0]).extend(m_start[v1]).extend(m_end[v1]);
        points.triangle_tree.query(sweep.min(), sweep.max(), [&](std::uint32_t t) {
            const Eigen::Vector3i& f = points.triangles[t];
            if (held(f)) return;
            const Eigen::Vector3d& origin = p[static_cast<std::size_t>(f[0])];
            const Eigen::Vector3d normal = (p[static_cast<std::size_t>(f[1])] - origin).cross(p[static_cast<std::size_t>(f[2])] - origin);
            const auto [a0, a1] = heights(normal, origin, v0);
            const auto [b0, b1] = heights(normal, origin, v1);
            if (plane_entry(a0, a1, b0, b1, 1e-9 * normal.norm()) >= std::min(toi, 1.0 + 1e-9) || !reachable(f, from, points, speed)) return;
            for (int j = 0; j < 3; ++j) { // a surface edge shared by two triangles is tested from both
                const Eigen::Vector3d &a = p[static_cast<std::size_t>(f[j])], &b = p[static_cast<std::size_t>(f[(j + 1) % 3])];
                if (sweep.intersects(Eigen::AlignedBox3d(a).extend(b)))
                    toi = std::min(toi, translating ? translating_edge_edge_toi({m_start[v0], m_start[v1]}, move, {a, b}, ccd, toi)
                                                    : edge_edge_toi(Points{m_start[v0], m_start[v1], a, b}, Points{m_end[v0], m_end[v1], a, b}, ccd, toi));
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
