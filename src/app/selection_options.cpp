#include "app/selection_options.hpp"

#include "core/error.hpp"

#include <CLI/CLI.hpp>

namespace vox::app {

io::Selection SelectionOptions::to_selection() const
{
    if (!labels.empty() && !threshold.empty()) throw InputError("--label and --threshold cannot be combined");
    if (!threshold.empty()) return io::parse_threshold(threshold);
    io::Selection s;
    s.labels = labels;
    return s;
}

void add_selection_options(CLI::App& cmd, SelectionOptions& options)
{
    cmd.add_option("--label", options.labels, "Keep voxels with these stored labels (comma-separated)")
        ->delimiter(',');
    cmd.add_option("--threshold", options.threshold,
                   "Keep voxels whose scaled value (e.g. Hounsfield units) is in LO[:HI], inclusive; label 1");
}

void add_mesh_options(CLI::App& cmd, MeshOptions& options)
{
    cmd.add_option("--voxel-size", options.voxel_mm, "Meshes: voxel edge in mm (default: longest side / 128)")
        ->check(CLI::PositiveNumber);
    cmd.add_option("--scale", options.mm_per_unit, "Meshes: millimetres per file unit (default 1)")
        ->check(CLI::PositiveNumber);
}

io::ImportOptions import_options(const SelectionOptions& selection, const MeshOptions& mesh)
{
    io::ImportOptions o;
    o.selection = selection.to_selection();
    o.voxel_mm = mesh.voxel_mm;
    o.mm_per_unit = mesh.mm_per_unit;
    return o;
}

void require_vdb_extension(const std::string& path)
{
    if (path.size() < 4 || path.compare(path.size() - 4, 4, ".vdb") != 0)
        throw InputError(path + ": the output must be an OpenVDB file ending in .vdb");
}

} // namespace vox::app
