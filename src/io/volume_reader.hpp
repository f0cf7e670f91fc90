#pragma once
// Reading scan volumes of any supported format into a Volume.

#include "io/volume.hpp"

#include <string>

namespace vox::io {

/// INRIMAGE-4 (.inr, .inr.gz). Header up to the line "##}", keys XDIM YDIM ZDIM VDIM TYPE PIXSIZE
/// CPU VX VY VZ (and XO YO ZO when present); the frame is taken as LPS, axes aligned.
[[nodiscard]] Volume read_inr(const std::string& path);
/// NIfTI-1 and NIfTI-2 (.nii, .nii.gz) through libnifti2; RAS sform/qform converted to LPS. The
/// raw header (size and magic, dim, pixdim, datatype, bitpix, vox_offset) is checked by us first,
/// so a bad one gets our one-line error and never libnifti's console output.
[[nodiscard]] Volume read_nifti(const std::string& path);
/// MetaImage (.mhd with a raw data file, or .mha), including zlib CompressedData.
[[nodiscard]] Volume read_metaimage(const std::string& path);
/// NRRD (.nrrd, or .nhdr with a detached data file), raw and gzip encodings.
[[nodiscard]] Volume read_nrrd(const std::string& path);

/// True when the path's extension names a volume format read above (not .vdb).
[[nodiscard]] bool is_volume_path(const std::string& path);
/// Dispatches on the extension. Every failure is an InputError naming the file; every reader says
/// "no such file", "is a folder, not a file" and "is empty" the same way (check_input_file).
[[nodiscard]] Volume read_volume(const std::string& path);

} // namespace vox::io
