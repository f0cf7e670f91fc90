#pragma once
// Builds the object a scene describes, and checks the parts of the scene that need it.

#include "grid/label_grid.hpp"
#include "grid/elastic_material.hpp"
#include "io/scene.hpp"

#include <map>
#include <vector>

namespace vox::io {

/// The labelled voxels of the scene's object (a scan and its selection, a phantom, or a mesh).
/// Errors name the scene and its "object" key, then the problem.
[[nodiscard]] grid::LabelGrid load_scene_object(const Scene& scene);
/// The same without the scene's name in front of errors.
[[nodiscard]] grid::LabelGrid build_scene_object(const Scene& scene);

/// Throws the scene's InputError ("constraints[2].box_mm: holds no voxel centre ...") when a
/// constraint box holds no material: no voxel centre of the object lies in it.
void check_constraints(const Scene& scene, const grid::LabelGrid& labels);

/// Labels that appear in the object but have no material of their own, and material labels the
/// object does not hold (usually a typo in the scene).
struct MaterialCoverage {
    std::vector<std::int32_t> using_default;
    std::vector<std::int32_t> unused;
};
[[nodiscard]] MaterialCoverage material_coverage(const Scene& scene, const grid::LabelGrid& labels);

} // namespace vox::io

namespace vox::io {

/// The grid's material table for a scene: index 0 is the default material, then one entry per
/// label with its own material; `index_of(label)` maps a voxel label to its entry.
struct MaterialTable {
    std::vector<grid::ElasticMaterial> materials;
    std::vector<Material> scene_materials; ///< the scene's entries, in the same order
    std::map<std::int32_t, std::int32_t> label_index;
    [[nodiscard]] std::int32_t index_of(std::int32_t label) const
    {
        const auto it = label_index.find(label);
        return it == label_index.end() ? 0 : it->second;
    }
};
[[nodiscard]] grid::ElasticMaterial to_voxel_material(const Material& m);
[[nodiscard]] MaterialTable material_table(const Scene& scene);
/// The table of scenes without a materials entry (and of files given without a scene).
[[nodiscard]] MaterialTable default_material_table();

} // namespace vox::io
