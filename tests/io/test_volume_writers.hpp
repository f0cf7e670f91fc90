#pragma once
// Writers used only by tests: they produce the same volume through other formats, so each reader
// can be checked against an independent route. Also what tests need to write files by hand (voxel
// bytes, gzip) and to check where voxels land.

#include "io/volume.hpp"

#include <Eigen/Core>

#include <cstdint>
#include <initializer_list>
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

/// The little-endian bytes of int16 values, in order.
[[nodiscard]] std::string le16(std::initializer_list<std::int16_t> values);
/// The big-endian bytes of int16 values, in order.
[[nodiscard]] std::string be16(std::initializer_list<std::int16_t> values);
/// `data` as a gzip stream (NRRD's gzip encoding).
[[nodiscard]] std::string gzip(const std::string& data);

/// The world position, mm, of the centre of voxel (i, j, k): index_to_world * (i, j, k, 1).
[[nodiscard]] Eigen::Vector3d world(const io::Volume& v, double i, double j, double k);

} // namespace vox::test
