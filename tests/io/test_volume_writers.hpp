#pragma once
// Writers used only by tests: they produce the same volume through other formats, so each reader
// can be checked against an independent route.

#include "io/volume.hpp"

#include <string>

namespace vox::test {

/// NIfTI-1 through libnifti2's own writer (gzip when the path ends in .gz). The LPS transform is
/// converted to RAS and stored as sform (code 1) and as qform when it is a rotation.
void write_nifti(const io::Volume& v, const std::string& path);
/// MetaImage: .mha (data inline) or .mhd + .raw; `compressed` uses zlib CompressedData.
void write_metaimage(const io::Volume& v, const std::string& path, bool compressed);
/// NRRD with "space: left-posterior-superior"; encoding "raw" or "gzip".
void write_nrrd(const io::Volume& v, const std::string& path, const std::string& encoding);
/// INRIMAGE-4 with a 256-byte header (axes aligned; the transform must be diagonal + origin).
void write_inr(const io::Volume& v, const std::string& path);

} // namespace vox::test
