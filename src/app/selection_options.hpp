#pragma once
// The --series, --label and --threshold options shared by the subcommands that read volumes, and
// the piece options (--components, --min-voxels, --seed-mm) that apply to volumes and meshes alike.

#include "io/object_import.hpp"
#include "io/selection.hpp"

#include <optional>

#include <string>
#include <vector>

namespace CLI {
class App;
}

namespace vox::app {

struct SelectionOptions {
    std::vector<std::int32_t> labels;
    std::string threshold;
    std::string components; ///< "largest" or N
    std::uint64_t min_voxels = 0;
    std::vector<std::string> seeds_mm; ///< "X,Y,Z" each
    std::string series;                ///< DICOM folders: --series N|UID
    std::vector<std::string> segments; ///< 3D Slicer segmentations: --segment NAME,...
    /// Throws InputError when both are given, the threshold text is malformed, or a piece option
    /// is.
    [[nodiscard]] io::Selection to_selection() const;
};

void add_selection_options(CLI::App& cmd, SelectionOptions& options);

/// --voxel-size and --scale, for subcommands that may read meshes.
struct MeshOptions {
    std::optional<double> voxel_mm;
    double mm_per_unit = 1.0;
};
void add_mesh_options(CLI::App& cmd, MeshOptions& options);

/// What io::import_object needs from both groups of options.
[[nodiscard]] io::ImportOptions import_options(const SelectionOptions& selection, const MeshOptions& mesh);

/// Throws InputError unless `path` ends in .vdb.
void require_vdb_extension(const std::string& path);

} // namespace vox::app
