#include "io/object_import.hpp"

#include "core/error.hpp"
#include "core/log.hpp"
#include "io/dicom_reader.hpp"
#include "io/segmentation.hpp"
#include "io/file_bytes.hpp"
#include "io/mesh.hpp"
#include "io/mesh_info.hpp"
#include "io/mesh_voxelizer.hpp"
#include "io/text_parsing.hpp"
#include "io/volume_reader.hpp"

#include <algorithm>
#include <cctype>
#include <cmath>

namespace vox::io {
bool is_mesh_path(const std::string& path)
{
    const std::string ext = detail::lower_extension(path);
    return ext == ".obj" || ext == ".ply" || ext == ".stl" || ext == ".off";
}

grid::LabelGrid import_object(const std::string& path, const ImportOptions& options)
{
    const bool dicom = !is_mesh_path(path) && !is_volume_path(path) && detail::lower_extension(path) != ".vdb" &&
                       is_dicom_path(path);
    if (is_segmentation_path(path)) {
        const Selection& s = options.selection;
        if (!s.labels.empty() || s.threshold_min || !s.bands.empty())
            throw file_error(path, "a 3D Slicer segmentation is selected by segment (--segment NAME), not by label or threshold");
        grid::LabelGrid picked = read_segmentation(path, s.segments);
        return s.pieces.empty() ? std::move(picked) : select_pieces(picked, s.pieces, path);
    }
    if (!options.selection.segments.empty())
        throw file_error(path, "--segment picks segments of a 3D Slicer segmentation (.seg.nrrd); this is not one");
    if (!options.series.empty() && !dicom)
        throw file_error(path, "--series picks a series of a DICOM folder; this is not one");
    if (dicom) return select_voxels(read_dicom(path, options.series), options.selection);
    if (is_mesh_path(path)) {
        if (!options.selection.empty())
            throw file_error(path, "--label and --threshold select voxels of volumes; a mesh is voxelised whole");
        const TriangleMesh mesh = read_mesh(path, options.mm_per_unit);
        const MeshInfo info = mesh_info(mesh);
        const double h = options.voxel_mm ? *options.voxel_mm : default_voxel_mm(info);
        VoxelizeOptions voxelize;
        voxelize.name = path;
        grid::LabelGrid grid = voxelize_mesh(mesh, h, voxelize);
        if (!options.voxel_mm) log::info("{}: voxel size {:.6g} mm (longest side / 128; set --voxel-size)", path, h);
        grid.set_metadata("source", path);
        return options.selection.pieces.empty() ? std::move(grid) : select_pieces(grid, options.selection.pieces, path);
    }
    if (options.voxel_mm || options.mm_per_unit != 1.0)
        throw file_error(path, "--voxel-size and --scale apply to meshes; a volume keeps its own voxels");
    if (detail::lower_extension(path) == ".vdb") {
        check_input_file(path); // the same "no such file", "is a folder", "is empty" as every reader
        return select_labels(grid::LabelGrid::load(path), options.selection, path);
    }
    if (is_volume_path(path)) return select_voxels(read_volume(path), options.selection);
    throw file_error(path, "unknown file type (expected a volume .inr[.gz] .nii[.gz] .mhd .mha .nrrd .nhdr .vdb, "
                           "a DICOM folder or file, or a mesh .obj .ply .stl .off)");
}

} // namespace vox::io
