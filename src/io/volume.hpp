#pragma once
// A dense scalar volume as read from a scan file, before selection turns it into labelled voxels.

#include <Eigen/Core>
#include <Eigen/LU>

#include <array>
#include <cstddef>
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

namespace vox::io {

/// Voxel storage types the readers accept.
enum class ScalarType { u8, i8, u16, i16, u32, i32, f32, f64 };

[[nodiscard]] std::size_t scalar_size(ScalarType t);
[[nodiscard]] const char* scalar_name(ScalarType t);
[[nodiscard]] bool is_integer(ScalarType t);

/// A dense volume: voxel (i, j, k) is stored at i + dims[0] * (j + dims[1] * k), in native byte
/// order, and has its centre at world point index_to_world * (i, j, k, 1), in millimetres in the
/// LPS frame (x towards the patient's left, y posterior, z superior), as ITK and 3D Slicer use.
/// A NIfTI file's own placement as read: its sform and qform codes and the qform's matrix (index
/// to RAS mm), so that a label map written back on its grid says what the scan said. The sform's
/// matrix is the volume's index_to_world (or the qform's, when the sform is not set).
struct NiftiTransforms {
    int sform_code = 0;
    int qform_code = 0;
    Eigen::Matrix4d qform_ras = Eigen::Matrix4d::Identity();

    /// As a label grid keeps it in its metadata ("nifti_transforms"): the codes, then the qform's
    /// 16 numbers row by row.
    [[nodiscard]] std::string text() const;
    /// From text(); nullopt for "" or text that is not that.
    [[nodiscard]] static std::optional<NiftiTransforms> parse(const std::string& text);
};

struct Volume {
    std::array<std::int64_t, 3> dims{0, 0, 0};
    Eigen::Matrix4d index_to_world = Eigen::Matrix4d::Identity(); ///< affine, last row (0 0 0 1)
    ScalarType type = ScalarType::u8;
    double scale_slope = 1.0;  ///< scaled value = slope * stored + intercept (NIfTI scl_*)
    double scale_intercept = 0.0;
    std::vector<std::byte> data; ///< dims product * scalar_size(type) bytes
    std::string source;          ///< the file it came from, for messages
    std::optional<NiftiTransforms> nifti; ///< a NIfTI file's codes and qform; empty for other formats

    [[nodiscard]] std::int64_t voxel_count() const { return dims[0] * dims[1] * dims[2]; }
    /// The stored value of voxel number `n` (linear index), converted to double.
    [[nodiscard]] double stored(std::int64_t n) const;
    /// The scaled value: slope * stored + intercept (Hounsfield units for CT).
    [[nodiscard]] double scaled(std::int64_t n) const { return scale_slope * stored(n) + scale_intercept; }
    /// Voxel spacing along each index axis, mm (column norms of the linear part).
    [[nodiscard]] Eigen::Vector3d spacing() const;
};

/// Checks what every reader must guarantee: positive dimensions, a finite affine transform whose
/// axes have positive length and are not degenerate, and a data size matching the dimensions.
/// Throws InputError naming the volume's source.
void validate(const Volume& v);

/// Checks that a file's raw voxel data, `held` bytes of it, is exactly what `v.dims` and `v.type`
/// need. `what` names the data in messages. Throws InputError "WHAT: truncated: holds ..." when it
/// is shorter, "WHAT: holds ...: the header does not describe this data" when it is longer.
void check_voxel_bytes(const Volume& v, std::uint64_t held, const std::string& what);

/// Swaps the byte order of every voxel in place (for big-endian files).
void swap_bytes(Volume& v);

/// Builds index_to_world from spacing, direction cosines (columns = index axes in world) and the
/// world position of voxel (0, 0, 0)'s centre.
[[nodiscard]] Eigen::Matrix4d make_index_to_world(const Eigen::Vector3d& spacing,
                                                  const Eigen::Matrix3d& direction,
                                                  const Eigen::Vector3d& origin);

} // namespace vox::io
