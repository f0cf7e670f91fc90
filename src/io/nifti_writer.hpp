#pragma once
// Writes a volume as NIfTI-1 (.nii, or gzip-compressed .nii.gz), the format 3D Slicer, ITK and
// nibabel read. Our world frame is LPS; NIfTI's is RAS, so the sform and qform written are the
// volume's index-to-world with x and y negated.

#include "io/volume.hpp"

#include <filesystem>

namespace vox::io {

/// Writes `v` to `path` (.nii or .nii.gz, decided by the name) atomically: on failure nothing is
/// left at `path`. Throws InputError for another extension or a transform NIfTI cannot hold.
void write_nifti(const Volume& v, const std::filesystem::path& path);

} // namespace vox::io
