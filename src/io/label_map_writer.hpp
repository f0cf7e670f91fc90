#pragma once
// Labelled voxels written back as the label maps medical tools read, on the grid of the scan
// they came from, so that 3D Slicer or ITK lays them over the scan with no registration: 3D
// Slicer segmentations (.seg.nrrd: one segment per label with its name, colour and ID), NRRD
// (.nrrd) and NIfTI (.nii, .nii.gz) label maps.

#include "grid/label_grid.hpp"

#include <filesystem>
#include <string>

namespace vox::io {

/// True for .seg.nrrd, .nrrd, .nii and .nii.gz names (any case).
[[nodiscard]] bool is_label_map_path(const std::string& path);

/// Writes `labels` to `path` (the format by its name) atomically. The grid written is the scan's
/// whole grid when the labels carry its size ("scan_dims" metadata, set on import) and lie in it,
/// else the box of the active voxels; its index-to-world is the labels' own (in LPS; NIfTI's is
/// written as RAS). Voxels are uint8 when every label fits, else int16 or int32. A .seg.nrrd names
/// each label by its segment (the "segments" metadata of io/segmentation.hpp; a label without one
/// becomes "label L"), a segment whose voxels were all cut away kept with an empty extent. Throws
/// InputError naming the path for another extension or when there is no voxel.
void write_label_map(const grid::LabelGrid& labels, const std::filesystem::path& path);

} // namespace vox::io
