#pragma once
// Which pieces (6-connected components, grid/voxel_pieces.hpp) of the selected voxels an object
// keeps, as 3D Slicer's islands tools choose them: the largest, the N largest, those a constraint
// box holds, those holding given points; and a least size.

#include "grid/voxel_pieces.hpp"

#include <Eigen/Geometry>

#include <cstdint>
#include <string>
#include <vector>

namespace vox::io {

struct PieceSelection {
    enum class Components {
        all,     ///< no "components" key
        largest, ///< "largest": the largest piece
        count,   ///< N: the N largest
        held,    ///< "held": those with a voxel reaching into a constraint box
    };
    Components components = Components::all;
    std::uint32_t count = 0;
    /// "seed_mm": pieces holding one of these world points (mm) are kept too.
    std::vector<Eigen::Vector3d> seeds_mm;
    /// "min_voxels": of the pieces picked, those smaller are dropped.
    std::uint64_t min_voxels = 0;
    /// "held": the scene's constraint boxes (world mm), filled in by the scene reader.
    std::vector<Eigen::AlignedBox3d> held_boxes;

    [[nodiscard]] bool empty() const { return components == Components::all && seeds_mm.empty() && min_voxels == 0; }
    /// "the largest piece", "pieces held by a constraint, of at least 50 voxels": for messages.
    [[nodiscard]] std::string describe() const;
};

/// Per piece: whether the centre of one of its voxels lies in one of `boxes` (world mm, closed):
/// the material a constraint with that box holds.
[[nodiscard]] std::vector<bool> pieces_in_boxes(const grid::LabelGrid& labels, const grid::VoxelPieces& pieces,
                                                const std::vector<Eigen::AlignedBox3d>& boxes);

/// Per piece: whether `selection` keeps it. `components` and `seed_mm` pick pieces (every piece
/// when neither is given; the union when both are), then `min_voxels` drops the small ones.
/// Throws InputError naming `source` when a seed lies in no voxel or nothing is kept.
[[nodiscard]] std::vector<bool> kept_pieces(const grid::LabelGrid& labels, const grid::VoxelPieces& pieces,
                                            const PieceSelection& selection, const std::string& source);

/// `labels` with only the pieces `selection` keeps (itself, cloned, when the selection is empty).
[[nodiscard]] grid::LabelGrid select_pieces(const grid::LabelGrid& labels, const PieceSelection& selection,
                                            const std::string& source);

/// 266098 as "266,098", for counts in messages.
[[nodiscard]] std::string count_text(std::uint64_t n);

/// "3 pieces: 1 (266,098 voxels, 323,309 mm3), 2 (...)...": a short summary for logs.
[[nodiscard]] std::string describe_pieces(const grid::VoxelPieces& pieces, std::size_t at_most = 5);

} // namespace vox::io
