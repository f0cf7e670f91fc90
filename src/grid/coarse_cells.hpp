#pragma once
// Coarse cells of a label grid: at level L, fine voxel (i, j, k) belongs to cell
// (i >> L, j >> L, k >> L) (arithmetic shift, so negative indices floor). A cell's corners, where
// the level-L element nodes sit, are at index coordinates (I * 2^L - 1/2, ...) and so on.

#include "grid/label_grid.hpp"

#include <vector>

namespace vox::grid {

/// The cells at `level` (0..6) holding at least one active voxel, sorted lexicographically.
[[nodiscard]] std::vector<Coord> occupied_cells(const LabelGrid& labels, int level);

/// World position (mm) of corner `corner` (bits 0, 1, 2 = +x, +y, +z) of cell `cell` at `level`.
[[nodiscard]] Eigen::Vector3d cell_corner_world(const LabelGrid& labels, const Coord& cell, int level, int corner);

} // namespace vox::grid
