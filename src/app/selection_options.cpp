#include "app/selection_options.hpp"

#include "core/error.hpp"

#include <CLI/CLI.hpp>

#include <cstdlib>
#include <sstream>

namespace vox::app {

namespace {

io::PieceSelection piece_selection(const SelectionOptions& o)
{
    io::PieceSelection p;
    if (o.components == "largest") {
        p.components = io::PieceSelection::Components::largest;
    } else if (o.components == "held") {
        throw InputError("--components held keeps the pieces a constraint box holds; only a scene has constraints "
                         "(\"select\": {\"components\": \"held\"})");
    } else if (!o.components.empty()) {
        char* end = nullptr;
        const long n = std::strtol(o.components.c_str(), &end, 10);
        if (end != o.components.c_str() + o.components.size() || n < 1 || n > 1000000000)
            throw InputError("--components " + o.components + ": expected \"largest\" or a number of pieces N >= 1");
        p.components = io::PieceSelection::Components::count;
        p.count = static_cast<std::uint32_t>(n);
    }
    p.min_voxels = o.min_voxels;
    for (const std::string& text : o.seeds_mm) {
        Eigen::Vector3d point;
        std::istringstream in(text);
        char comma1 = 0, comma2 = 0;
        if (!(in >> point.x() >> comma1 >> point.y() >> comma2 >> point.z()) || comma1 != ',' || comma2 != ',' ||
            !(in >> std::ws).eof() || !point.allFinite())
            throw InputError("--seed-mm " + text + ": expected X,Y,Z in world millimetres");
        p.seeds_mm.push_back(point);
    }
    return p;
}

} // namespace

io::Selection SelectionOptions::to_selection() const
{
    if (!labels.empty() && !threshold.empty()) throw InputError("--label and --threshold cannot be combined");
    io::Selection s;
    if (!threshold.empty()) s = io::parse_threshold(threshold);
    s.labels = labels;
    s.segments = segments;
    if (!segments.empty() && (!labels.empty() || !threshold.empty()))
        throw InputError("--segment cannot be combined with --label or --threshold (a segmentation is selected by segment)");
    s.pieces = piece_selection(*this);
    return s;
}

void add_selection_options(CLI::App& cmd, SelectionOptions& options)
{
    cmd.add_option("--series", options.series,
                   "DICOM folders holding several series: the one to read, by its number in `info` or its UID");
    cmd.add_option("--segment", options.segments,
                   "3D Slicer segmentations (.seg.nrrd): keep these segments, by name or ID (comma-separated; labels "
                   "1, 2, ... in this order, the later winning where they overlap)")
        ->delimiter(',');
    cmd.add_option("--label", options.labels, "Keep voxels with these stored labels (comma-separated)")
        ->delimiter(',');
    cmd.add_option("--threshold", options.threshold,
                   "Keep voxels whose scaled value (e.g. Hounsfield units) is in LO[:HI], inclusive; label 1");
    cmd.add_option("--components", options.components,
                   "Keep pieces (6-connected): \"largest\", or N for the N largest");
    cmd.add_option("--min-voxels", options.min_voxels, "Drop pieces of fewer voxels")->check(CLI::PositiveNumber);
    cmd.add_option("--seed-mm", options.seeds_mm, "Keep the piece holding this world point X,Y,Z (mm); repeatable")
        ->allow_extra_args(false);
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
    o.series = selection.series;
    return o;
}

void require_vdb_extension(const std::string& path)
{
    if (path.size() < 4 || path.compare(path.size() - 4, 4, ".vdb") != 0)
        throw InputError(path + ": the output must be an OpenVDB file ending in .vdb");
}

} // namespace vox::app
