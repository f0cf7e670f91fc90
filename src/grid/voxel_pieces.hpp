#pragma once
// The pieces of an object's voxels: 6-connected components (voxels sharing a face), as the
// branched grid's pieces. A CT's bone threshold gives the skull, the scanner's head holder and
// loose fragments as separate pieces; selection keeps some (io/piece_selection.hpp) and `check`
// lists them.

#include "grid/label_grid.hpp"

#include <Eigen/Core>

#include <cstdint>
#include <vector>

namespace vox::grid {

struct VoxelPiece {
    std::uint64_t voxels = 0;
    double volume_mm3 = 0.0;
    IndexBox bounds;            ///< voxel indices, inclusive
    Eigen::Vector3d min_mm;     ///< world bounding box of the voxels' extents
    Eigen::Vector3d max_mm;
};

/// Every active voxel's piece. Pieces are numbered by size, largest first (ties: the piece whose
/// first voxel in z, y, x order comes first), so "piece 0" is the largest whatever the file order.
class VoxelPieces {
public:
    static constexpr std::uint32_t none = 0xffffffffu;

    explicit VoxelPieces(const LabelGrid& labels);

    [[nodiscard]] const std::vector<VoxelPiece>& pieces() const { return m_pieces; }
    [[nodiscard]] std::size_t size() const { return m_pieces.size(); }
    /// The piece of the voxel at `ijk`, or `none` when it is not active.
    [[nodiscard]] std::uint32_t piece_at(const Coord& ijk) const;
    /// Every active voxel with its piece, sorted by (z, y, x).
    [[nodiscard]] const std::vector<Coord>& voxels() const { return m_coords; }
    [[nodiscard]] const std::vector<std::uint32_t>& voxel_pieces() const { return m_piece; }

private:
    std::vector<Coord> m_coords;
    std::vector<std::uint32_t> m_piece;
    std::vector<VoxelPiece> m_pieces;
};

/// A copy of `labels` with only the voxels of the pieces flagged in `keep` (indexed by piece).
[[nodiscard]] LabelGrid keep_pieces(const LabelGrid& labels, const VoxelPieces& pieces, const std::vector<bool>& keep);

} // namespace vox::grid
