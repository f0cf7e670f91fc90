// Mesh summary: area and volume in one pass over the triangles, edge topology from the sorted
// list of edge uses, holes as connected components of the boundary edges.

#include "io/mesh_info.hpp"

#include "core/union_find.hpp"

#include <Eigen/Geometry>

#include <algorithm>
#include <cstdint>
#include <unordered_map>
#include <utility>
#include <vector>

namespace vox::io {
namespace {

/// One use of an undirected edge by a triangle: `key` packs (min, max) vertex index, `forward` says
/// whether the triangle walks it from min to max.
struct EdgeUse {
    std::uint64_t key;
    bool forward;
    bool operator<(const EdgeUse& o) const { return key < o.key; }
};

std::vector<EdgeUse> sorted_edge_uses(const TriangleMesh& mesh)
{
    std::vector<EdgeUse> uses;
    uses.reserve(3 * mesh.triangles.size());
    for (const Eigen::Vector3i& t : mesh.triangles) {
        for (int c = 0; c < 3; ++c) {
            const auto a = static_cast<std::uint32_t>(t[c]);
            const auto b = static_cast<std::uint32_t>(t[(c + 1) % 3]);
            uses.push_back({(std::uint64_t{std::min(a, b)} << 32) | std::max(a, b), a < b});
        }
    }
    std::sort(uses.begin(), uses.end());
    return uses;
}

/// Fills the edge counts, `closed`, `consistently_oriented`, the boundary loops and their cap area.
void summarise_edges(const TriangleMesh& mesh, const Eigen::Vector3d& centre, MeshInfo& info)
{
    const std::vector<EdgeUse> uses = sorted_edge_uses(mesh);
    std::vector<std::pair<std::uint32_t, std::uint32_t>> boundary; // directed as their triangle walks them
    info.consistently_oriented = true;
    for (std::size_t i = 0; i < uses.size();) {
        std::size_t j = i;
        long long balance = 0;
        for (; j < uses.size() && uses[j].key == uses[i].key; ++j) balance += uses[j].forward ? 1 : -1;
        const std::size_t count = j - i;
        ++info.edges;
        if (count == 1) {
            const auto lo = static_cast<std::uint32_t>(uses[i].key >> 32);
            const auto hi = static_cast<std::uint32_t>(uses[i].key & 0xffffffffu);
            boundary.emplace_back(uses[i].forward ? lo : hi, uses[i].forward ? hi : lo);
        } else if (balance != 0) {
            info.consistently_oriented = false;
        }
        if (count > 2) ++info.non_manifold_edges;
        i = j;
    }
    info.boundary_edges = boundary.size();
    info.closed = !mesh.triangles.empty() && info.boundary_edges == 0 && info.non_manifold_edges == 0;

    UnionFind loops(mesh.vertices.size()); // boundary edges grouped into loops
    for (const auto& [a, b] : boundary) loops.unite(a, b);
    std::unordered_map<std::uint32_t, Eigen::Vector3d> loop_area; // by the loop's representative vertex
    for (const auto& [a, b] : boundary) {
        const Eigen::Vector3d pa = mesh.vertices[a] - centre;
        const Eigen::Vector3d pb = mesh.vertices[b] - centre;
        auto [it, inserted] = loop_area.try_emplace(loops.find(a), Eigen::Vector3d::Zero());
        it->second += 0.5 * pa.cross(pb);
    }
    info.boundary_loops = loop_area.size();
    for (const auto& [root, area] : loop_area) info.boundary_cap_area_mm2 += area.norm();

    UnionFind pieces(mesh.vertices.size());
    for (const Eigen::Vector3i& t : mesh.triangles) {
        pieces.unite(static_cast<std::uint32_t>(t[0]), static_cast<std::uint32_t>(t[1]));
        pieces.unite(static_cast<std::uint32_t>(t[0]), static_cast<std::uint32_t>(t[2]));
    }
    std::unordered_map<std::uint32_t, bool> roots;
    for (const Eigen::Vector3i& t : mesh.triangles) roots.emplace(pieces.find(static_cast<std::uint32_t>(t[0])), true);
    info.components = roots.size();
}

} // namespace

MeshInfo mesh_info(const TriangleMesh& mesh)
{
    MeshInfo info;
    info.vertices = mesh.vertices.size();
    info.triangles = mesh.triangles.size();
    if (mesh.triangles.empty()) return info;

    Eigen::AlignedBox3d box;
    for (const Eigen::Vector3i& t : mesh.triangles)
        for (int c = 0; c < 3; ++c) box.extend(mesh.vertices[static_cast<std::size_t>(t[c])]);
    info.bbox_min = box.min();
    info.bbox_max = box.max();
    // Corners relative to the box centre keep the volume's terms small: less cancellation.
    const Eigen::Vector3d centre = box.center();
    for (const Eigen::Vector3i& t : mesh.triangles) {
        const Eigen::Vector3d a = mesh.vertices[static_cast<std::size_t>(t[0])] - centre;
        const Eigen::Vector3d b = mesh.vertices[static_cast<std::size_t>(t[1])] - centre;
        const Eigen::Vector3d c = mesh.vertices[static_cast<std::size_t>(t[2])] - centre;
        info.area_mm2 += 0.5 * (b - a).cross(c - a).norm();
        info.enclosed_volume_mm3 += a.dot(b.cross(c)) / 6.0;
    }
    summarise_edges(mesh, centre, info);
    return info;
}

} // namespace vox::io
