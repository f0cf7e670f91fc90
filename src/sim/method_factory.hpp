#pragma once
// The scene's method (`solver.type`), built on its object's voxels at its level; "levels":
// "auto" chooses the level first (sim/level_choice.hpp) and says why.

#include "sim/level_choice.hpp"
#include "sim/method.hpp"

#include <memory>
#include <optional>

namespace vox::grid {
class LabelGrid;
}

namespace vox::sim {

struct OpenedMethod {
    std::unique_ptr<Method> method;
    std::optional<LevelChoice> choice; ///< how "levels": "auto" chose
};

/// Throws the scene's InputError for what the method cannot simulate, or a box that holds no voxel centre.
[[nodiscard]] OpenedMethod open_method(const io::Scene& scene, std::shared_ptr<const grid::LabelGrid> labels);

} // namespace vox::sim
