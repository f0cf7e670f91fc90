#pragma once
// The fine region of a scene simulated on two levels ("levels": {"fine", "coarse",
// "fine_radius_mm"}): the coarse cells reaching within fine_radius_mm of a tool's outer shape
// where the run starts (its first key frame; the shape's box, grown by the radius).

#include "grid/mixed_levels.hpp"
#include "io/scene.hpp"

#include <memory>

namespace vox::sim {

/// The two-level selection of `grid` for `scene`. Throws the scene's InputError when no tool has
/// a key frame to place the region by. Requires scene.object.mixed_levels.
[[nodiscard]] std::unique_ptr<grid::MixedLevels> mixed_region(const io::Scene& scene, const grid::BranchedGrid& grid);

} // namespace vox::sim
