#include "contact/tool_shape.hpp"

#include "contact/convex_hull.hpp"
#include "core/error.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <map>
#include <utility>

namespace vox::contact {
namespace {


/// The convex polygon moved out by `margin` (each edge along its outward normal).
std::vector<Eigen::Vector2d> offset_polygon(const std::vector<Eigen::Vector2d>& poly, double margin)
{
    const std::size_t n = poly.size();
    std::vector<Eigen::Vector2d> out(n);
    for (std::size_t i = 0; i < n; ++i) {
        const Eigen::Vector2d prev = poly[(i + n - 1) % n], here = poly[i], next = poly[(i + 1) % n];
        const Eigen::Vector2d e0 = (here - prev).normalized(), e1 = (next - here).normalized();
        const Eigen::Vector2d n0(e0.y(), -e0.x()), n1(e1.y(), -e1.x());
        // The corner of the two moved edges: here + m (n0 + n1) / (1 + n0.n1).
        out[i] = here + margin * (n0 + n1) / (1.0 + n0.dot(n1));
    }
    return out;
}

/// Closest point to p on triangle abc (Ericson, Real-Time Collision Detection, 5.1.5).
Eigen::Vector3d closest_on_triangle(const Eigen::Vector3d& p, const Eigen::Vector3d& a, const Eigen::Vector3d& b,
                                    const Eigen::Vector3d& c)
{
    const Eigen::Vector3d ab = b - a, ac = c - a, ap = p - a;
    const double d1 = ab.dot(ap), d2 = ac.dot(ap);
    if (d1 <= 0 && d2 <= 0) return a;
    const Eigen::Vector3d bp = p - b;
    const double d3 = ab.dot(bp), d4 = ac.dot(bp);
    if (d3 >= 0 && d4 <= d3) return b;
    const double vc = d1 * d4 - d3 * d2;
    if (vc <= 0 && d1 >= 0 && d3 <= 0) return a + d1 / (d1 - d3) * ab;
    const Eigen::Vector3d cp = p - c;
    const double d5 = ab.dot(cp), d6 = ac.dot(cp);
    if (d6 >= 0 && d5 <= d6) return c;
    const double vb = d5 * d2 - d1 * d6;
    if (vb <= 0 && d2 >= 0 && d6 <= 0) return a + d2 / (d2 - d6) * ac;
    const double va = d3 * d6 - d5 * d4;
    if (va <= 0 && (d4 - d3) >= 0 && (d5 - d6) >= 0) return b + (d4 - d3) / ((d4 - d3) + (d5 - d6)) * (c - b);
    const double denom = 1.0 / (va + vb + vc);
    return a + ab * (vb * denom) + ac * (vc * denom);
}

/// Solid angle of triangle abc seen from the origin (Van Oosterom and Strackee 1983).
double solid_angle(const Eigen::Vector3d& a, const Eigen::Vector3d& b, const Eigen::Vector3d& c)
{
    const double la = a.norm(), lb = b.norm(), lc = c.norm();
    const double numerator = a.dot(b.cross(c));
    const double denominator = la * lb * lc + a.dot(b) * lc + b.dot(c) * la + c.dot(a) * lb;
    return 2.0 * std::atan2(numerator, denominator);
}

/// Outward orientation for a convex mesh around its centre.
void orient_outward(TriangleMesh& m, const Eigen::Vector3d& centre)
{
    for (Eigen::Vector3i& t : m.triangles) {
        const Eigen::Vector3d &a = m.positions[t[0]], &b = m.positions[t[1]], &c = m.positions[t[2]];
        if ((b - a).cross(c - a).dot((a + b + c) / 3.0 - centre) < 0.0) std::swap(t[1], t[2]);
    }
}

TriangleMesh icosphere(double radius, int detail)
{
    const double p = (1.0 + std::sqrt(5.0)) / 2.0;
    TriangleMesh m;
    for (const auto& v : {Eigen::Vector3d(-1, p, 0), Eigen::Vector3d(1, p, 0), Eigen::Vector3d(-1, -p, 0),
                          Eigen::Vector3d(1, -p, 0), Eigen::Vector3d(0, -1, p), Eigen::Vector3d(0, 1, p),
                          Eigen::Vector3d(0, -1, -p), Eigen::Vector3d(0, 1, -p), Eigen::Vector3d(p, 0, -1),
                          Eigen::Vector3d(p, 0, 1), Eigen::Vector3d(-p, 0, -1), Eigen::Vector3d(-p, 0, 1)})
        m.positions.push_back(v.normalized());
    m.triangles = {{0, 11, 5}, {0, 5, 1},  {0, 1, 7},   {0, 7, 10}, {0, 10, 11}, {1, 5, 9}, {5, 11, 4},
                   {11, 10, 2}, {10, 7, 6}, {7, 1, 8},   {3, 9, 4},  {3, 4, 2},   {3, 2, 6}, {3, 6, 8},
                   {3, 8, 9},   {4, 9, 5},  {2, 4, 11},  {6, 2, 10}, {8, 6, 7},   {9, 8, 1}};
    for (int d = 0; d < detail; ++d) {
        std::map<std::pair<int, int>, int> middle;
        auto mid = [&](int a, int b) {
            const auto key = std::minmax(a, b);
            const auto found = middle.find(key);
            if (found != middle.end()) return found->second;
            m.positions.push_back((m.positions[a] + m.positions[b]).normalized());
            const int id = static_cast<int>(m.positions.size()) - 1;
            middle.emplace(key, id);
            return id;
        };
        std::vector<Eigen::Vector3i> next;
        for (const Eigen::Vector3i& t : m.triangles) {
            const int ab = mid(t[0], t[1]), bc = mid(t[1], t[2]), ca = mid(t[2], t[0]);
            next.insert(next.end(), {{t[0], ab, ca}, {t[1], bc, ab}, {t[2], ca, bc}, {ab, bc, ca}});
        }
        m.triangles = std::move(next);
    }
    for (Eigen::Vector3d& v : m.positions) v *= radius;
    orient_outward(m, Eigen::Vector3d::Zero());
    return m;
}

} // namespace

ToolShape ToolShape::box(const Eigen::Vector3d& size)
{
    ToolShape s;
    s.m_kind = Kind::box;
    s.m_size = size;
    const double hx = size.x() / 2, hz = size.z() / 2;
    s.set_profile({{-hx, -hz}, {hx, -hz}, {hx, hz}, {-hx, hz}});
    s.m_bounds = Eigen::AlignedBox3d(-size / 2, size / 2);
    s.set_outline();
    return s;
}

ToolShape ToolShape::scalpel(const Eigen::Vector3d& size)
{
    ToolShape s = box(size);
    s.m_kind = Kind::scalpel;
    const double hx = size.x() / 2, hz = size.z() / 2;
    // The front rises at 45 degrees from the point; a blade shorter than it is tall becomes the
    // 45-degree triangle whose slanted side meets the back at height size.x() above the bottom.
    const double top_front = hx - size.z();
    s.set_profile({{-hx, -hz}, {hx, -hz}, {top_front, hz}, {-hx, hz}});
    if (top_front <= -hx) {
        const double top = std::min(hz, -hz + size.x());
        s.set_profile({{-hx, -hz}, {hx, -hz}, {-hx, top}});
        s.m_bounds.max().z() = top;
    }
    s.set_outline();
    return s;
}

ToolShape ToolShape::sphere(double radius)
{
    ToolShape s;
    s.m_kind = Kind::sphere;
    s.m_radius = radius;
    s.m_bounds = Eigen::AlignedBox3d(Eigen::Vector3d::Constant(-radius), Eigen::Vector3d::Constant(radius));
    return s;
}

ToolShape ToolShape::cylinder(double radius, double length)
{
    ToolShape s;
    s.m_kind = Kind::cylinder;
    s.m_radius = radius;
    s.m_length = length;
    s.m_bounds = Eigen::AlignedBox3d(Eigen::Vector3d(-radius, -radius, -length / 2), Eigen::Vector3d(radius, radius, length / 2));
    s.set_outline();
    return s;
}

ToolShape ToolShape::from_mesh(TriangleMesh mesh)
{
    if (mesh.triangles.empty()) throw InputError("tool mesh: it has no triangle");
    ToolShape s;
    s.m_kind = Kind::mesh;
    s.m_bounds.setEmpty();
    for (const Eigen::Vector3d& p : mesh.positions) s.m_bounds.extend(p);
    s.m_mesh = std::move(mesh);
    s.set_outline();
    return s;
}

namespace {
constexpr std::size_t k_max_outline = 256;
constexpr int k_circle_sides = 48;
} // namespace

void ToolShape::set_outline()
{
    m_outline.clear();
    switch (m_kind) {
    case Kind::box:
    case Kind::scalpel:
        for (const Eigen::Vector2d& q : m_profile)
            for (const double y : {-0.5 * m_size.y(), 0.5 * m_size.y()}) m_outline.emplace_back(q.x(), y, q.y());
        break;
    case Kind::cylinder: {
        const double r = m_radius / std::cos(M_PI / k_circle_sides); // circumscribed: never smaller than the circle
        for (int k = 0; k < k_circle_sides; ++k) {
            const double a = 2.0 * M_PI * k / k_circle_sides;
            for (const double z : {-0.5 * m_length, 0.5 * m_length}) m_outline.emplace_back(r * std::cos(a), r * std::sin(a), z);
        }
        break;
    }
    case Kind::mesh:
        if (m_mesh.positions.size() <= k_max_outline) m_outline = m_mesh.positions;
        break;
    case Kind::sphere:
        break;
    }
}

double ToolShape::shadow_area(const Eigen::Vector3d& along, double margin) const noexcept
{
    if (m_kind == Kind::sphere) return M_PI * (m_radius + margin) * (m_radius + margin);
    if (m_outline.empty() || !(along.squaredNorm() > 0.0)) return std::numeric_limits<double>::infinity();
    // The outline projected on a plane across `along`, its convex hull (in fixed buffers), and
    // the hull grown by the margin (Steiner: area + perimeter r + pi r^2).
    const Eigen::Vector3d n = along.normalized(), u = n.unitOrthogonal(), v = n.cross(u);
    std::array<Eigen::Vector2d, k_max_outline> p;
    const std::size_t count = m_outline.size();
    for (std::size_t k = 0; k < count; ++k) p[k] = {u.dot(m_outline[k]), v.dot(m_outline[k])};
    std::array<Eigen::Vector2d, 2 * k_max_outline> hull;
    const std::size_t h = convex_hull(std::span<Eigen::Vector2d>(p.data(), count), std::span<Eigen::Vector2d>(hull));
    double area = 0.0, perimeter = 0.0;
    for (std::size_t k = 0; k < h; ++k) {
        const Eigen::Vector2d &a = hull[k], &b = hull[(k + 1) % h];
        area += 0.5 * (a.x() * b.y() - b.x() * a.y());
        perimeter += (b - a).norm();
    }
    return std::abs(area) + perimeter * margin + M_PI * margin * margin;
}

void ToolShape::set_profile(std::vector<Eigen::Vector2d> profile)
{
    m_profile = std::move(profile);
    m_edges.clear();
    for (std::size_t i = 0; i < m_profile.size(); ++i) {
        const Eigen::Vector2d a = m_profile[i], e = m_profile[(i + 1) % m_profile.size()] - a;
        m_edges.push_back({a, e, Eigen::Vector2d(e.y(), -e.x()).normalized(), 1.0 / e.squaredNorm()}); // outward for CCW
    }
}

double ToolShape::prism_distance(const Eigen::Vector3d& p, Eigen::Vector3d* gradient) const noexcept
{
    // The exact signed distance to the convex profile in the x-z plane, and its unit gradient g2:
    // inside, the nearest edge is the nearest plane; outside, the nearest point of the edges
    // (squared distances compared, one square root).
    const Eigen::Vector2d q(p.x(), p.z());
    double inside = -std::numeric_limits<double>::infinity(), outside2 = std::numeric_limits<double>::infinity();
    Eigen::Vector2d inside_normal(1, 0), nearest = m_edges.front().a;
    for (const ProfileEdge& edge : m_edges) {
        const Eigen::Vector2d from_a = q - edge.a;
        const double plane = edge.normal.dot(from_a);
        if (plane > inside) {
            inside = plane;
            inside_normal = edge.normal;
        }
        const Eigen::Vector2d c = edge.a + std::clamp(from_a.dot(edge.e) * edge.inverse_length2, 0.0, 1.0) * edge.e;
        const double d2 = (q - c).squaredNorm();
        if (d2 < outside2) {
            outside2 = d2;
            nearest = c;
        }
    }
    Eigen::Vector2d g2 = inside_normal;
    double d2 = inside;
    if (inside > 0.0) {
        d2 = std::sqrt(outside2);
        if (d2 > 0.0) g2 = (q - nearest) / d2;
    }
    const double sy = p.y() >= 0.0 ? 1.0 : -1.0;
    const double dy = std::abs(p.y()) - m_size.y() / 2;
    double d;
    Eigen::Vector3d g;
    if (d2 <= 0.0 && dy <= 0.0) {
        d = std::max(d2, dy);
        g = d2 >= dy ? Eigen::Vector3d(g2.x(), 0, g2.y()) : Eigen::Vector3d(0, sy, 0);
    } else {
        const double a = std::max(d2, 0.0), b = std::max(dy, 0.0);
        d = std::sqrt(a * a + b * b); // mm: no overflow to guard against (std::hypot is several times slower)
        g = (Eigen::Vector3d(a * g2.x(), b * sy, a * g2.y()) / d);
    }
    if (gradient) *gradient = g;
    return d;
}

double ToolShape::mesh_distance(const Eigen::Vector3d& p, Eigen::Vector3d* gradient) const noexcept
{
    double best = std::numeric_limits<double>::infinity();
    Eigen::Vector3d nearest = p, face_normal(0, 0, 1);
    double winding = 0.0;
    for (const Eigen::Vector3i& t : m_mesh.triangles) {
        const Eigen::Vector3d &a = m_mesh.positions[t[0]], &b = m_mesh.positions[t[1]], &c = m_mesh.positions[t[2]];
        const Eigen::Vector3d q = closest_on_triangle(p, a, b, c);
        const double d = (p - q).squaredNorm();
        if (d < best) {
            best = d;
            nearest = q;
            face_normal = (b - a).cross(c - a).normalized();
        }
        winding += solid_angle(a - p, b - p, c - p);
    }
    const bool inside = winding / (4.0 * M_PI) > 0.5;
    const double distance = std::sqrt(best);
    if (gradient) *gradient = distance > 1e-12 ? Eigen::Vector3d((p - nearest) / distance * (inside ? -1.0 : 1.0)) : face_normal;
    return inside ? -distance : distance;
}

double ToolShape::signed_distance(const Eigen::Vector3d& p, Eigen::Vector3d* gradient) const noexcept
{
    switch (m_kind) {
    case Kind::box: {
        // The prism's distance for a rectangular profile, in closed form (a blade's, at every
        // 1 kHz tick for every point near it): q = |p| - half size per axis; inside, the nearest
        // face; outside, the length of q's positive part.
        const Eigen::Array3d sign = (p.array() >= 0.0).select(Eigen::Array3d::Ones(), -Eigen::Array3d::Ones());
        const Eigen::Array3d q = p.array().abs() - 0.5 * m_size.array();
        if ((q <= 0.0).all()) {
            int axis = 0;
            const double d = q.maxCoeff(&axis);
            if (gradient) *gradient = sign[axis] * Eigen::Vector3d::Unit(axis);
            return d;
        }
        const Eigen::Array3d out = q.max(0.0);
        const double d = std::sqrt(out.matrix().squaredNorm());
        if (gradient) *gradient = (out * sign / d).matrix();
        return d;
    }
    case Kind::scalpel:
        return prism_distance(p, gradient);
    case Kind::sphere: {
        const double r = p.norm();
        if (gradient) *gradient = r > 0.0 ? Eigen::Vector3d(p / r) : Eigen::Vector3d(0, 0, 1);
        return r - m_radius;
    }
    case Kind::cylinder: {
        // Distances to the side (radial) and to the end planes (axial), combined as for a box.
        const double rho = std::sqrt(p.x() * p.x() + p.y() * p.y());
        const Eigen::Vector2d radial = rho > 0.0 ? Eigen::Vector2d(p.x() / rho, p.y() / rho) : Eigen::Vector2d(1, 0);
        const double dr = rho - m_radius, dz = std::abs(p.z()) - m_length / 2;
        const double sz = p.z() >= 0.0 ? 1.0 : -1.0;
        if (dr <= 0.0 && dz <= 0.0) {
            if (gradient) *gradient = dr >= dz ? Eigen::Vector3d(radial.x(), radial.y(), 0) : Eigen::Vector3d(0, 0, sz);
            return std::max(dr, dz);
        }
        const double a = std::max(dr, 0.0), b = std::max(dz, 0.0), d = std::sqrt(a * a + b * b);
        if (gradient) *gradient = Eigen::Vector3d(a * radial.x(), a * radial.y(), b * sz) / d;
        return d;
    }
    case Kind::mesh:
        return mesh_distance(p, gradient);
    }
    return 0.0;
}

Eigen::AlignedBox3d ToolShape::bounds(double margin) const
{
    const Eigen::Vector3d m = Eigen::Vector3d::Constant(margin);
    return Eigen::AlignedBox3d(m_bounds.min() - m, m_bounds.max() + m);
}

TriangleMesh ToolShape::mesh(double margin, int detail) const
{
    TriangleMesh m;
    switch (m_kind) {
    case Kind::box:
    case Kind::scalpel: {
        const std::vector<Eigen::Vector2d> poly = profile(margin);
        const int n = static_cast<int>(poly.size());
        const double hy = m_size.y() / 2 + margin;
        for (double y : {-hy, hy})
            for (const Eigen::Vector2d& q : poly) m.positions.emplace_back(q.x(), y, q.y());
        for (int i = 1; i + 1 < n; ++i) {
            m.triangles.emplace_back(0, i, i + 1);
            m.triangles.emplace_back(n, n + i, n + i + 1);
        }
        for (int i = 0; i < n; ++i) {
            const int j = (i + 1) % n;
            m.triangles.emplace_back(i, j, n + j);
            m.triangles.emplace_back(i, n + j, n + i);
        }
        Eigen::Vector3d centre = Eigen::Vector3d::Zero();
        for (const Eigen::Vector3d& p : m.positions) centre += p;
        orient_outward(m, centre / static_cast<double>(m.positions.size()));
        return m;
    }
    case Kind::sphere:
        return icosphere(m_radius + margin, detail);
    case Kind::cylinder: {
        const int sides = 8 << std::clamp(detail, 0, 4);
        const double r = m_radius + margin, h = m_length / 2 + margin;
        for (double z : {-h, h}) {
            m.positions.emplace_back(0.0, 0.0, z); // the end's centre
            for (int k = 0; k < sides; ++k) {
                const double a = 2.0 * M_PI * k / sides;
                m.positions.emplace_back(r * std::cos(a), r * std::sin(a), z);
            }
        }
        const int top = sides + 1;
        for (int k = 0; k < sides; ++k) {
            const int a = 1 + k, b = 1 + (k + 1) % sides;
            m.triangles.emplace_back(0, b, a);                   // bottom, seen from -z
            m.triangles.emplace_back(top, top + a, top + b);     // top
            m.triangles.emplace_back(a, b, top + b);             // side
            m.triangles.emplace_back(a, top + b, top + a);
        }
        orient_outward(m, Eigen::Vector3d::Zero());
        return m;
    }
    case Kind::mesh: {
        m = m_mesh;
        std::vector<Eigen::Vector3d> normal(m.positions.size(), Eigen::Vector3d::Zero());
        for (const Eigen::Vector3i& t : m.triangles) {
            const Eigen::Vector3d n = (m.positions[t[1]] - m.positions[t[0]]).cross(m.positions[t[2]] - m.positions[t[0]]);
            for (int k = 0; k < 3; ++k) normal[t[k]] += n;
        }
        for (std::size_t i = 0; i < m.positions.size(); ++i)
            if (normal[i].norm() > 0.0) m.positions[i] += margin * normal[i].normalized();
        return m;
    }
    }
    return m;
}

std::vector<Eigen::Vector2d> ToolShape::profile(double margin) const
{
    if (m_kind != Kind::box && m_kind != Kind::scalpel) return {};
    return offset_polygon(m_profile, margin);
}

double PlacedShape::signed_distance(const Eigen::Vector3d& world, Eigen::Vector3d* gradient) const noexcept
{
    const double d = shape->signed_distance(orientation.conjugate() * (world - position), gradient);
    if (gradient) *gradient = orientation * *gradient;
    return d;
}

Eigen::AlignedBox3d PlacedShape::world_bounds(double margin) const
{
    const Eigen::AlignedBox3d local = shape->bounds(margin);
    Eigen::AlignedBox3d out;
    out.setEmpty();
    for (int c = 0; c < 8; ++c) out.extend(position + orientation * local.corner(static_cast<Eigen::AlignedBox3d::CornerType>(c)));
    return out;
}

} // namespace vox::contact
