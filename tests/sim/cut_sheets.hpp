#pragma once
// What one stroke of a separating tool opened in the branched grid, as issue-level checks count
// it: the sheets (opened faces joined across voxel edges), pairs of parallel opened faces one voxel
// apart (a second sheet beside the first), and slivers (pieces of fewer than 27 voxels).

#include "core/union_find.hpp"
#include "grid/fine_voxels.hpp"

#include <array>
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
    return out;
}

} // namespace vox::test
