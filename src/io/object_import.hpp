#pragma once
// One entry point from any input (scan volume, DICOM folder, .vdb label grid, or surface mesh) to the
// labelled voxels of an object.

#include "grid/label_grid.hpp"
#include "io/selection.hpp"

#include <optional>
#include <string>

namespace vox::io {

struct ImportOptions {
    Selection selection;             ///< volumes and .vdb files
    std::optional<double> voxel_mm;  ///< meshes: voxel edge (default: longest side / 128)
    double mm_per_unit = 1.0;        ///< meshes: file units to millimetres
    std::string series;              ///< DICOM folders: the series' number or UID ("": the only one)
};

/// True for the mesh extensions read by read_mesh (.obj .ply .stl .off).
[[nodiscard]] bool is_mesh_path(const std::string& path);

/// Reads and selects (volumes, .vdb) or voxelises (meshes). Throws InputError naming the file, or
/// naming the option, for options that do not apply to the input's kind.
[[nodiscard]] grid::LabelGrid import_object(const std::string& path, const ImportOptions& options);

} // namespace vox::io
