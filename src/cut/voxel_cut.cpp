#include "cut/voxel_cut.hpp"

#include <algorithm>
#include <cmath>
#include <deque>
#include <unordered_map>
#include <unordered_set>

namespace vox::cut {
namespace {

/// The section of a shape grown by `margin` in its own frame (y = 0), as a convex polygon.
std::vector<Eigen::Vector3d> section(const contact::ToolShape& shape, double margin)
{
    std::vector<Eigen::Vector3d> out;
    switch (shape.kind()) {
    case contact::ToolShape::Kind::sphere: {
        const double r = shape.bounds(margin).max().x();
        for (int k = 0; k < 24; ++k) {
            const double a = 2.0 * M_PI * k / 24;
            out.emplace_back(r * std::cos(a), 0.0, r * std::sin(a));
        }
        return out;
    }
    case contact::ToolShape::Kind::box:
    case contact::ToolShape::Kind::scalpel:
        for (const Eigen::Vector2d& q : shape.profile(margin)) out.emplace_back(q.x(), 0.0, q.y());
        return out;
    case contact::ToolShape::Kind::cylinder: // its section through the axis is a rectangle
    case contact::ToolShape::Kind::mesh: {
        const Eigen::AlignedBox3d b = shape.bounds(margin);
        return {{b.min().x(), 0, b.min().z()}, {b.max().x(), 0, b.min().z()}, {b.max().x(), 0, b.max().z()}, {b.min().x(), 0, b.max().z()}};
    }
    }
    return out;
}

} // namespace

std::vector<std::uint32_t> voxels_inside(const ModelSurface& surface, const std::vector<Eigen::Vector3d>& node_positions,
                                         const contact::PlacedShape& inner, const std::vector<std::uint32_t>& seed_vertices,
                                         double reach_mm)
{
    const grid::FineVoxels& voxels = surface.grid().voxels();
    std::unordered_set<std::uint32_t> seen;
    std::deque<std::uint32_t> queue;
    std::vector<std::uint32_t> out;
    for (std::uint32_t v : seed_vertices) {
        const std::uint32_t voxel = surface.embedded().vertices()[v].voxel;
        if (voxels.alive(voxel) && seen.insert(voxel).second) queue.push_back(voxel);
    }
    // Seeds spread even when their own centre is outside: the blade has reached their surface and
    // may already hold the next layer's centres.
    std::unordered_set<std::uint32_t> seeds(seen);
    while (!queue.empty()) {
        const std::uint32_t v = queue.front();
        queue.pop_front();
        const bool inside = inner.signed_distance(surface.voxel_centre_mm(v, node_positions)) < reach_mm;
        if (inside) out.push_back(v);
        if (!inside && !seeds.count(v)) continue;
        voxels.for_each_link(v, [&](std::uint32_t u, int) {
            if (seen.insert(u).second) queue.push_back(u);
        });
    }
    return out;
}

Eigen::AlignedBox3d SweptSurface::bounds() const
{
    Eigen::AlignedBox3d b;
    b.setEmpty();
    for (const auto& t : triangles)
        for (const Eigen::Vector3d& p : t) b.extend(p);
    return b;
}

std::vector<Eigen::Vector3d> section_polygon(const contact::ToolShape& shape, double margin, const contact::PlacedShape& pose)
{
    std::vector<Eigen::Vector3d> polygon = section(shape, margin);
    for (Eigen::Vector3d& p : polygon) p = pose.position + pose.orientation * p;
    return polygon;
}

SweptSurface sweep_polygons(const std::vector<Eigen::Vector3d>& a, const std::vector<Eigen::Vector3d>& b, const Eigen::Vector3d& normal)
{
    const std::size_t n = a.size();
    SweptSurface s;
    s.normal = normal;
    bool moved = false;
    for (std::size_t i = 0; i < n; ++i) moved = moved || a[i] != b[i];
    for (std::size_t i = 1; i + 1 < n; ++i) { // the section at both ends (convex: a fan)
        s.triangles.push_back({a[0], a[i], a[i + 1]});
        if (moved) s.triangles.push_back({b[0], b[i], b[i + 1]});
    }
    // Whatever the section covered during the stroke and covers at neither end was crossed by its
    // boundary: the bands the edges sweep.
    if (moved)
        for (std::size_t i = 0; i < n; ++i) {
            const std::size_t j = (i + 1) % n;
            s.triangles.push_back({a[i], a[j], b[j]});
            s.triangles.push_back({a[i], b[j], b[i]});
        }
    return s;
}

SweptSurface sweep_section(const contact::ToolShape& shape, double margin, const contact::PlacedShape& from,
                           const contact::PlacedShape& to)
{
    return sweep_polygons(section_polygon(shape, margin, from), section_polygon(shape, margin, to),
                          to.orientation * Eigen::Vector3d::UnitY());
}

bool segment_crosses(const Eigen::Vector3d& p, const Eigen::Vector3d& q, const std::array<Eigen::Vector3d, 3>& t,
                     const Eigen::Vector3d& normal)
{
    const Eigen::Vector3d winding = (t[1] - t[0]).cross(t[2] - t[0]);
    if (winding.squaredNorm() == 0.0) return false; // a degenerate band (an edge moving along itself)
    const Eigen::Vector3d n = winding.dot(normal) < 0.0 ? Eigen::Vector3d(-winding) : winding; // the side rule's orientation
    const double sp = n.dot(p - t[0]), sq = n.dot(q - t[0]);
    // On the surface counts as +, to within 1e-9 of the segment's length: the triangles of one flat
    // section are coplanar only up to rounding, and a centre on it must fall on the same side of
    // all of them, or both pairs around it are cut (a one-voxel slab).
    const double on = 1e-9 * (q - p).norm() * n.norm();
    if ((sp >= -on) == (sq >= -on)) return false; // both on one side
    const Eigen::Vector3d x = p + (sp / (sp - sq)) * (q - p);
    // Inside the triangle, edges included: x on the inner side of each edge, as the triangle's own
    // winding (not the side rule's normal, which may be its opposite) orders them.
    for (int k = 0; k < 3; ++k)
        if ((t[(k + 1) % 3] - t[k]).cross(x - t[k]).dot(winding) < -1e-12 * winding.squaredNorm()) return false;
    return true;
}

Eigen::Vector3d mean_displacement_mm(const ModelSurface& surface, const std::vector<Eigen::Vector3d>& node_positions,
                                     const Eigen::AlignedBox3d& box)
{
    const fem::HexModel& model = surface.model();
    Eigen::Vector3d sum = Eigen::Vector3d::Zero();
    std::size_t count = 0;
    for (const fem::HexElement& el : model.elements()) {
        Eigen::AlignedBox3d deformed;
        deformed.setEmpty();
        for (std::uint32_t n : el.dof_node) deformed.extend(1e3 * node_positions[n]);
        if (!deformed.intersects(box)) continue;
        for (std::uint32_t n : el.dof_node) sum += 1e3 * (node_positions[n] - model.rest_positions()[n]);
        count += 8;
    }
    return count ? Eigen::Vector3d(sum / static_cast<double>(count)) : Eigen::Vector3d::Zero();
}

std::vector<std::pair<grid::Coord, int>> faces_crossed(const grid::FineVoxels& voxels, const SweptSurface& swept)
{
    std::vector<std::pair<grid::Coord, int>> out;
    if (swept.triangles.empty()) return out;
    // Every voxel whose rest centre lies within one voxel edge (along each axis) of the surface's
    // box: the lower voxel of any crossing pair.
    const Eigen::Matrix4d& to_world = voxels.index_to_world();
    const Eigen::Matrix3d to_index = to_world.topLeftCorner<3, 3>().inverse();
    const Eigen::AlignedBox3d box = swept.bounds();
    Eigen::AlignedBox3d index_box;
    index_box.setEmpty();
    for (int c = 0; c < 8; ++c)
        index_box.extend(to_index * (box.corner(static_cast<Eigen::AlignedBox3d::CornerType>(c)) - to_world.topRightCorner<3, 1>()));
    const grid::Coord first = (index_box.min().array() - 1.0).floor().cast<int>();
    const grid::Coord last = (index_box.max().array() + 1.0).ceil().cast<int>();
    auto rest = [&](const grid::Coord& c) {
        return voxels.world_mm(c.cast<double>());
    };
    // Each triangle's oriented plane, computed as segment_crosses does: a pair on one side of it
    // (most pairs, for most triangles) is passed over without the full test.
    std::vector<Eigen::Vector3d> plane_normal;
    for (const auto& t : swept.triangles) {
        const Eigen::Vector3d winding = (t[1] - t[0]).cross(t[2] - t[0]);
        plane_normal.push_back(winding.dot(swept.normal) < 0.0 ? Eigen::Vector3d(-winding) : winding);
    }
    for (int k = first.z(); k <= last.z(); ++k)
        for (int j = first.y(); j <= last.y(); ++j)
            for (int i = first.x(); i <= last.x(); ++i) {
                const grid::Coord c(i, j, k);
                const std::uint32_t v = voxels.find(c);
                if (v == grid::FineVoxels::missing) continue;
                const Eigen::Vector3d p = rest(c);
                for (int axis = 0; axis < 3; ++axis) {
                    const std::uint32_t u = voxels.connected_neighbour(v, axis);
                    if (u == grid::FineVoxels::missing) continue;
                    const Eigen::Vector3d q = rest(c + grid::Coord::Unit(axis));
                    const double on = 1e-9 * (q - p).norm();
                    for (std::size_t t = 0; t < swept.triangles.size(); ++t) {
                        const auto& tri = swept.triangles[t];
                        const double tolerance = on * plane_normal[t].norm();
                        if ((plane_normal[t].dot(p - tri[0]) >= -tolerance) == (plane_normal[t].dot(q - tri[0]) >= -tolerance)) continue;
                        if (segment_crosses(p, q, tri, swept.normal)) {
                            out.emplace_back(c, axis);
                            break;
                        }
                    }
                }
            }
    return out;
}

} // namespace vox::cut
