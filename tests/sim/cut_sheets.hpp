#pragma once
// What one stroke of a separating tool opened, as issue-level checks count it. Branched grid: the
// sheets (opened faces joined across voxel edges), pairs of parallel opened faces one voxel apart
// (a second sheet beside the first), and slivers (pieces of fewer than 27 voxels). Is-XFEM: the
// sheets (each crack's tetrahedra joined across the edges it crosses), tetrahedra cut twice along nearly
// the same direction (a second crack beside the first), and slivers (closed pieces of the surface
// enclosing less than 27 voxels' volume).

#include "core/union_find.hpp"
#include "grid/fine_voxels.hpp"
#include "isxfem/xfem_model.hpp"
#include "surface/embedded_surface.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <map>
#include <utility>
#include <vector>

namespace vox::test {

struct SheetCount {
    std::size_t faces = 0;
    std::size_t sheets = 0;
    std::size_t parallel_pairs = 0; ///< same axis, same place across it, one voxel apart along it
    std::size_t pieces = 0;
    std::size_t slivers = 0;        ///< pieces of fewer than 27 voxels
    std::size_t voxels = 0;         ///< alive voxels after the cut (branched grid)
};

/// `faces`: (voxel, axis) = the face between the voxel and its +axis neighbour.
inline SheetCount count_sheets(const grid::FineVoxels& voxels, const std::vector<std::pair<grid::Coord, int>>& faces)
{
    SheetCount out;
    // Unique faces; each face's four edges in doubled coordinates (a face centre is odd along its axis).
    std::map<std::array<int, 4>, std::size_t> index;
    for (const auto& [c, axis] : faces) index.emplace(std::array<int, 4>{c.x(), c.y(), c.z(), axis}, index.size());
    out.faces = index.size();
    UnionFind sets(index.size());
    std::map<std::array<int, 4>, std::size_t> edge_owner; // edge midpoint (doubled) and direction
    for (const auto& [f, k] : index) {
        const int axis = f[3];
        std::array<int, 3> centre{2 * f[0], 2 * f[1], 2 * f[2]};
        centre[static_cast<std::size_t>(axis)] += 1;
        for (int side = 0; side < 2; ++side)
            for (int sign = -1; sign <= 1; sign += 2) {
                const int across = (axis + 1 + side) % 3, along = (axis + 2 - side) % 3;
                std::array<int, 3> mid = centre;
                mid[static_cast<std::size_t>(across)] += sign;
                const std::array<int, 4> edge{mid[0], mid[1], mid[2], along};
                const auto [it, fresh] = edge_owner.emplace(edge, k);
                if (!fresh) sets.unite(static_cast<std::uint32_t>(it->second), static_cast<std::uint32_t>(k));
            }
        const std::array<int, 4> next{f[0] + (axis == 0), f[1] + (axis == 1), f[2] + (axis == 2), axis};
        out.parallel_pairs += index.count(next);
    }
    for (std::size_t k = 0; k < index.size(); ++k) out.sheets += sets.find(static_cast<std::uint32_t>(k)) == k;
    // Pieces of the voxels through their connected faces.
    UnionFind voxel_sets(voxels.slots());
    for (std::uint32_t v = 0; v < voxels.slots(); ++v)
        if (voxels.alive(v)) voxels.for_each_link(v, [&](std::uint32_t n, int) { voxel_sets.unite(v, n); });
    std::map<std::uint32_t, std::size_t> size;
    for (std::uint32_t v = 0; v < voxels.slots(); ++v)
        if (voxels.alive(v)) ++size[voxel_sets.find(v)];
    out.pieces = size.size();
    for (const auto& [r, n] : size) out.slivers += n < 27;
    out.voxels = voxels.alive_count();
    return out;
}

/// The same for an Is-XFEM model and its closed surface (world mm), `voxel_mm3` one voxel's volume.
inline SheetCount count_cracks(const isxfem::XfemModel& model, const surface::SurfaceMesh& surface, double voxel_mm3)
{
    SheetCount out;
    // Each crack's tetrahedra, joined where two share a face (three nodes).
    std::map<int, std::vector<std::size_t>> cut_by;
    for (std::size_t t = 0; t < model.elements().size(); ++t) {
        const auto& cuts = model.elements()[t].cuts;
        for (const isxfem::ElementCut& c : cuts) cut_by[c.id].push_back(t);
        out.faces += cuts.size();
        if (cuts.size() == 2 && std::abs(model.crack_normal(cuts[0].id, t).dot(model.crack_normal(cuts[1].id, t))) > 0.95)
            ++out.parallel_pairs;
    }
    // Two of a crack's tetrahedra join where they share an edge the crack crosses (its nodes on
    // the crack's two sides in both): their crack polygons meet on it.
    for (const auto& [id, tets] : cut_by) {
        UnionFind sets(tets.size());
        std::map<std::array<std::uint32_t, 2>, std::size_t> edge_owner;
        for (std::size_t k = 0; k < tets.size(); ++k) {
            const isxfem::XfemElement& el = model.elements()[tets[k]];
            const isxfem::ElementCut& cut = el.cuts[static_cast<std::size_t>(el.cut_index(id))];
            for (std::size_t a = 0; a < 4; ++a)
                for (std::size_t b = a + 1; b < 4; ++b) {
                    if (cut.node_side[a] == cut.node_side[b]) continue;
                    const std::array<std::uint32_t, 2> edge{std::min(el.node[a], el.node[b]), std::max(el.node[a], el.node[b])};
                    const auto [it, fresh] = edge_owner.emplace(edge, k);
                    if (!fresh) sets.unite(static_cast<std::uint32_t>(it->second), static_cast<std::uint32_t>(k));
                }
        }
        for (std::size_t k = 0; k < tets.size(); ++k) out.sheets += sets.find(static_cast<std::uint32_t>(k)) == k;
    }
    // Pieces: the closed surface's connected parts, each with the volume it encloses.
    UnionFind parts(surface.positions.size());
    for (const Eigen::Vector3i& t : surface.triangles) {
        parts.unite(static_cast<std::uint32_t>(t[0]), static_cast<std::uint32_t>(t[1]));
        parts.unite(static_cast<std::uint32_t>(t[0]), static_cast<std::uint32_t>(t[2]));
    }
    std::map<std::uint32_t, double> volume;
    for (const Eigen::Vector3i& t : surface.triangles)
        volume[parts.find(static_cast<std::uint32_t>(t[0]))] +=
            surface.positions[static_cast<std::size_t>(t[0])].dot(surface.positions[static_cast<std::size_t>(t[1])].cross(surface.positions[static_cast<std::size_t>(t[2])])) / 6.0;
    out.pieces = volume.size();
    for (const auto& [root, v] : volume) out.slivers += v < 27.0 * voxel_mm3;
    return out;
}

} // namespace vox::test
