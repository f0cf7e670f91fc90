#pragma once
// The fine region of a scene simulated on two levels ("levels": {"fine", "coarse",
// "fine_radius_mm"}): the coarse cells whose material lies within fine_radius_mm of a tool's outer
// shape. It starts around the tools' first key frames and then follows the tools: each frame the
// cells the tools' reach meets (over the object as it is deformed now) are refined, and cells the
// tools have left are coarsened again.

#include "fem/hex_model.hpp"
#include "grid/mixed_levels.hpp"
#include "io/scene.hpp"

#include <Eigen/Geometry>

#include <memory>
#include <span>
#include <vector>

namespace vox::sim {

/// Coarse cells (index at the coarse level) the fine region covers, sorted, each once: a cell with
/// superimposed elements is refined whole.
using RegionCells = std::vector<grid::Coord>;

/// The region where the run starts: the cells whose rest box meets a tool's outer shape, grown by
/// fine_radius_mm, at the tool's first key frame in "script" (none without a script: a device
/// run's region starts empty and gathers around the tools as they come). Requires
/// scene.object.mixed_levels.
[[nodiscard]] RegionCells starting_region(const io::Scene& scene, const grid::BranchedGrid& grid);

/// The region with the tools' reach at `reach_mm` (world boxes of their outer shapes grown by
/// fine_radius_mm) over `model` at `positions_m`: the cells whose elements' current box meets a
/// reach, and those of `current` that still come within half a coarse cell of one (so that a tool
/// resting near a cell's border does not refine and coarsen it frame after frame).
[[nodiscard]] RegionCells followed_region(const grid::BranchedGrid& grid, const fem::HexModel& model,
                                          const std::vector<Eigen::Vector3d>& positions_m, std::span<const Eigen::AlignedBox3d> reach_mm,
                                          const RegionCells& current);

/// The two-level selection of `grid` refining `cells`.
[[nodiscard]] std::unique_ptr<grid::MixedLevels> mixed_levels(const grid::BranchedGrid& grid, const io::MixedLevelsSpec& spec,
                                                              const RegionCells& cells);

} // namespace vox::sim
