#include "io/scene_object.hpp"

#include "core/error.hpp"
#include "io/box.hpp"
#include "grid/coarse_cells.hpp"
#include "grid/phantom.hpp"
#include "io/object_import.hpp"

#include <Eigen/Geometry>

#include <sstream>

namespace vox::io {

grid::LabelGrid load_scene_object(const Scene& scene)
{
    // Problems found while building the object (an empty selection, a phantom too large, a mesh
    // that encloses nothing) are reported against the scene's "object" key too.
    try {
        return build_scene_object(scene);
    } catch (const InputError& e) {
        throw scene.error("object", e.what());
    }
}

namespace {

/// "unheld_pieces": "leave_out": only the pieces a constraint box reaches.
grid::LabelGrid leave_out_unheld(const Scene& scene, grid::LabelGrid labels)
{
    if (scene.object.unheld != UnheldPieces::leave_out) return labels;
    if (scene.constraints.empty())
        throw InputError("unheld_pieces: \"leave_out\" would leave out the whole object: no constraint holds any of it");
    PieceSelection held;
    held.components = PieceSelection::Components::held;
    held.held_boxes = scene.object.select.pieces.held_boxes; // the constraint boxes
    return select_pieces(labels, held, labels.metadata("source"));
}

grid::LabelGrid build_object_voxels(const Scene& scene);

} // namespace

grid::LabelGrid build_scene_object(const Scene& scene)
{
    return leave_out_unheld(scene, build_object_voxels(scene));
}

namespace {

grid::LabelGrid build_object_voxels(const Scene& scene)
{
    const SceneObject& o = scene.object;
    switch (o.kind) {
    case ObjectKind::phantom: {
        grid::LabelGrid g = grid::make_phantom(o.phantom);
        g.set_metadata("source", std::string("phantom ") + grid::phantom_shape_name(o.phantom.shape));
        return g;
    }
    case ObjectKind::mesh: {
        ImportOptions options;
        options.voxel_mm = o.voxel_mm;
        options.mm_per_unit = o.scale_mm_per_unit;
        return import_object(o.file.string(), options);
    }
    case ObjectKind::volume: {
        ImportOptions options;
        options.selection = o.select;
        options.series = o.series;
        return import_object(o.file.string(), options);
    }
    }
    throw scene.error("object", "unknown object kind");
}

} // namespace

void check_constraints(const Scene& scene, const grid::LabelGrid& labels)
{
    if (scene.constraints.empty()) return;
    // A support holds the material whose voxel centres lie in its box, at every level alike.
    const std::size_t n = scene.constraints.size();
    std::vector<unsigned char> holds(n, 0);
    Eigen::AlignedBox3d span;
    labels.for_each_active([&](const grid::Coord& ijk, std::int32_t) {
        const Eigen::Vector3d p = labels.index_to_world(ijk.cast<double>());
        span.extend(p);
        for (std::size_t c = 0; c < n; ++c)
            holds[c] = holds[c] || in_box(p, scene.constraints[c].box_min_mm, scene.constraints[c].box_max_mm);
    });
    for (std::size_t c = 0; c < n; ++c) {
        if (holds[c]) continue;
        std::ostringstream os;
        os << "holds no voxel centre of the object (a support holds the material whose voxel centres lie in its box; they span ("
           << span.min().x() << ", " << span.min().y() << ", " << span.min().z() << ") to (" << span.max().x() << ", "
           << span.max().y() << ", " << span.max().z() << ") mm)";
        throw scene.error("constraints[" + std::to_string(c) + "].box_mm", os.str());
    }
}

MaterialCoverage material_coverage(const Scene& scene, const grid::LabelGrid& labels)
{
    MaterialCoverage m;
    const auto hist = labels.label_histogram();
    for (const auto& [label, n] : hist)
        if (!scene.label_materials.count(label)) m.using_default.push_back(label);
    for (const auto& [label, mat] : scene.label_materials)
        if (!hist.count(label)) m.unused.push_back(label);
    return m;
}

} // namespace vox::io

namespace vox::io {

grid::ElasticMaterial to_voxel_material(const Material& m)
{
    return {grid::lame_from_young_poisson(m.youngs_modulus_pa, m.poisson_ratio), m.density_kg_m3};
}

MaterialTable material_table(const Scene& scene)
{
    MaterialTable t;
    t.materials.push_back(to_voxel_material(scene.default_material));
    t.scene_materials.push_back(scene.default_material);
    for (const auto& [label, material] : scene.label_materials) {
        t.label_index[label] = static_cast<std::int32_t>(t.materials.size());
        t.materials.push_back(to_voxel_material(material));
        t.scene_materials.push_back(material);
    }
    return t;
}

MaterialTable default_material_table()
{
    MaterialTable t;
    t.materials.push_back(to_voxel_material(Material{}));
    t.scene_materials.push_back(Material{});
    return t;
}

} // namespace vox::io
