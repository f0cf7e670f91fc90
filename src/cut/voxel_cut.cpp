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
    case contact::ToolShape::Kind::scalpel: {
        // The mesh's first ring is the profile at -y; keep x and z.
        const contact::TriangleMesh m = shape.mesh(margin);
        for (std::size_t i = 0; i < m.positions.size() / 2; ++i) out.emplace_back(m.positions[i].x(), 0.0, m.positions[i].z());
        return out;
    }
    case contact::ToolShape::Kind::mesh: {
        const Eigen::AlignedBox3d b = shape.bounds(margin);
        return {{b.min().x(), 0, b.min().z()}, {b.max().x(), 0, b.min().z()}, {b.max().x(), 0, b.max().z()}, {b.min().x(), 0, b.max().z()}};
    }
    }
    return out;
}

struct CoordHash {
    std::size_t operator()(std::uint32_t v) const { return v * 0x9E3779B1u; }
};

} // namespace

std::vector<std::uint32_t> voxels_inside(const ModelSurface& surface, const std::vector<Eigen::Vector3d>& node_positions,
                                         const contact::PlacedShape& inner, const std::vector<std::uint32_t>& seed_vertices)
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
        const bool inside = inner.signed_distance(surface.voxel_centre_mm(v, node_positions)) < 0.0;
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

SweptSurface sweep_section(const contact::ToolShape& shape, double margin, const contact::PlacedShape& from,
                           const contact::PlacedShape& to)
{
    const std::vector<Eigen::Vector3d> polygon = section(shape, margin);
    const std::size_t n = polygon.size();
    SweptSurface s;
    s.normal = to.orientation * Eigen::Vector3d::UnitY();
    std::vector<Eigen::Vector3d> a(n), b(n);
    for (std::size_t i = 0; i < n; ++i) {
        a[i] = from.position + from.orientation * polygon[i];
        b[i] = to.position + to.orientation * polygon[i];
    }
    for (std::size_t i = 1; i + 1 < n; ++i) { // the section at both ends (convex: a fan)
        s.triangles.push_back({a[0], a[i], a[i + 1]});
        if ((to.position - from.position).norm() > 0.0 || !to.orientation.isApprox(from.orientation))
            s.triangles.push_back({b[0], b[i], b[i + 1]});
    }
    // Whatever the section covered during the stroke and covers at neither end was crossed by its
    // boundary: the bands the edges sweep.
    if ((to.position - from.position).norm() > 0.0 || !to.orientation.isApprox(from.orientation))
        for (std::size_t i = 0; i < n; ++i) {
            const std::size_t j = (i + 1) % n;
            s.triangles.push_back({a[i], a[j], b[j]});
            s.triangles.push_back({a[i], b[j], b[i]});
        }
    return s;
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

std::vector<std::pair<grid::Coord, int>> faces_crossed(const ModelSurface& surface, const std::vector<Eigen::Vector3d>& node_positions,
                                                       const SweptSurface& swept)
{
    std::vector<std::pair<grid::Coord, int>> out;
    if (swept.triangles.empty()) return out;
    const fem::HexModel& model = surface.model();
    const grid::BranchedGrid& grid = surface.grid();
    const grid::FineVoxels& voxels = grid.voxels();
    const int level = model.level();
    // Pairs are tested from their lower voxel, which may lie a whole (stretched) segment away
    // from the surface: two voxels of margin.
    Eigen::AlignedBox3d reach = swept.bounds();
    const double voxel_mm = 1e3 * voxels.voxel_size_m().maxCoeff();
    reach.extend(reach.min() - Eigen::Vector3d::Constant(2.0 * voxel_mm));
    reach.extend(reach.max() + Eigen::Vector3d::Constant(2.0 * voxel_mm));
    const Eigen::Matrix4d& to_world = voxels.index_to_world();
    const Eigen::Matrix3d to_index = to_world.topLeftCorner<3, 3>().inverse();
    std::unordered_map<std::uint32_t, Eigen::Vector3d, CoordHash> centre;
    auto centre_of = [&](std::uint32_t v) -> const Eigen::Vector3d& {
        auto found = centre.find(v);
        if (found == centre.end()) found = centre.emplace(v, surface.voxel_centre_mm(v, node_positions)).first;
        return found->second;
    };
    std::vector<std::uint32_t> candidates;
    for (std::uint32_t e = 0; e < model.elements().size(); ++e) {
        const fem::HexElement& el = model.elements()[e];
        Eigen::AlignedBox3d box;
        box.setEmpty();
        for (std::uint32_t n : el.dof_node) box.extend(1e3 * node_positions[n]);
        if (!box.intersects(reach)) continue;
        // Only voxels whose rest centre, moved by the element's mean displacement, can reach:
        // a trilinear displacement differs from the mean by at most the corners' spread.
        Eigen::Vector3d mean = Eigen::Vector3d::Zero();
        for (std::uint32_t n : el.dof_node) mean += 1e3 * (node_positions[n] - model.rest_positions()[n]) / 8.0;
        double spread = 0.0;
        for (std::uint32_t n : el.dof_node) spread = std::max(spread, (1e3 * (node_positions[n] - model.rest_positions()[n]) - mean).norm());
        const Eigen::Vector3d lo = reach.min() - mean - Eigen::Vector3d::Constant(spread);
        const Eigen::Vector3d hi = reach.max() - mean + Eigen::Vector3d::Constant(spread);
        Eigen::AlignedBox3d index_box;
        index_box.setEmpty();
        for (int c = 0; c < 8; ++c) {
            const Eigen::Vector3d corner((c & 1) ? hi.x() : lo.x(), (c & 2) ? hi.y() : lo.y(), (c & 4) ? hi.z() : lo.z());
            index_box.extend(to_index * (corner - to_world.topRightCorner<3, 1>()));
        }
        const grid::Coord cell = level == 0 ? voxels.coord(el.grid_element) : grid.level(level).elements[el.grid_element].cell;
        const int size = 1 << level;
        grid::Coord first, last;
        for (int a = 0; a < 3; ++a) {
            first[a] = std::max(cell[a] * size, static_cast<int>(std::ceil(index_box.min()[a] - 0.5)));
            last[a] = std::min(cell[a] * size + size - 1, static_cast<int>(std::floor(index_box.max()[a] + 0.5)));
        }
        for (int k = first.z(); k <= last.z(); ++k)
            for (int j = first.y(); j <= last.y(); ++j)
                for (int i = first.x(); i <= last.x(); ++i) {
                    const std::uint32_t v = voxels.find(grid::Coord(i, j, k));
                    if (v == grid::FineVoxels::missing) continue;
                    Eigen::Vector3d local;
                    if (surface.voxel_element(v, local) == e) candidates.push_back(v); // superimposed: its own element
                }
    }
    // Deformed centres: each voxel is on one side of the swept surface whatever pair it is tested
    // in (so the cut surface closes), and the cut meets the material where the user sees it.
    for (std::uint32_t v : candidates) {
        const Eigen::Vector3d p = centre_of(v);
        if (!reach.contains(p)) continue;
        for (int axis = 0; axis < 3; ++axis) {
            const std::uint32_t u = voxels.connected_neighbour(v, axis);
            if (u == grid::FineVoxels::missing) continue;
            const Eigen::Vector3d q = centre_of(u);
            for (const auto& t : swept.triangles)
                if (segment_crosses(p, q, t, swept.normal)) {
                    out.emplace_back(voxels.coord(v), axis);
                    break;
                }
        }
    }
    return out;
}

} // namespace vox::cut
