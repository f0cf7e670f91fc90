#pragma once
// Builds the object a scene describes, and checks the parts of the scene that need it.

#include "grid/label_grid.hpp"
#include "io/scene.hpp"

namespace vox::io {

/// The labelled voxels of the scene's object (a scan and its selection, a phantom, or a mesh).
[[nodiscard]] grid::LabelGrid load_scene_object(const Scene& scene);

/// Throws the scene's InputError ("constraints[2].box_mm: catches no node ...") when a constraint
/// box holds no element corner node at the scene's level.
void check_constraints(const Scene& scene, const grid::LabelGrid& labels);

/// Labels that appear in the object but have no material of their own, and material labels the
/// object does not hold (usually a typo in the scene).
struct MaterialCoverage {
    std::vector<std::int32_t> using_default;
    std::vector<std::int32_t> unused;
};
[[nodiscard]] MaterialCoverage material_coverage(const Scene& scene, const grid::LabelGrid& labels);

} // namespace vox::io
