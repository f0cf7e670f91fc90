// NIfTI-1/NIfTI-2 reader through libnifti2. The transform follows ITK (5.2 and later) and 3D Slicer:
// the sform when its code is set, else the qform when its code is set, else the voxel sizes alone;
// NIfTI's RAS world is converted to LPS by negating x and y. Unlike ITK we keep any shear of the
// sform instead of dropping it, so voxel centres land exactly where the file says.

#include "core/error.hpp"
#include "core/memory_limit.hpp"
#include "io/volume_reader.hpp"

#include <nifti2_io.h>

#include <cstring>
#include <filesystem>
#include <memory>
#include <mutex>

namespace vox::io {
namespace {

struct NiftiDeleter {
    void operator()(nifti_image* nim) const { nifti_image_free(nim); }
};
using NiftiPtr = std::unique_ptr<nifti_image, NiftiDeleter>;

ScalarType scalar_type(const std::string& path, int datatype)
{
    switch (datatype) {
    case DT_UINT8: return ScalarType::u8;
    case DT_INT8: return ScalarType::i8;
    case DT_UINT16: return ScalarType::u16;
    case DT_INT16: return ScalarType::i16;
    case DT_UINT32: return ScalarType::u32;
    case DT_INT32: return ScalarType::i32;
    case DT_FLOAT32: return ScalarType::f32;
    case DT_FLOAT64: return ScalarType::f64;
    default: break;
    }
    const char* name = nifti_datatype_string(datatype);
    throw file_error(path, std::string("unsupported voxel type ") + (name ? name : "?") + " (code " +
                               std::to_string(datatype) + ")");
}

Eigen::Matrix4d to_eigen(const nifti_dmat44& m)
{
    Eigen::Matrix4d t;
    for (int r = 0; r < 4; ++r)
        for (int c = 0; c < 4; ++c) t(r, c) = m.m[r][c];
    return t;
}

Eigen::Matrix4d ras_index_to_world(const nifti_image& nim)
{
    if (nim.sform_code > 0) return to_eigen(nim.sto_xyz);
    if (nim.qform_code > 0) return to_eigen(nim.qto_xyz);
    Eigen::Matrix4d t = Eigen::Matrix4d::Identity();
    t(0, 0) = nim.dx;
    t(1, 1) = nim.dy;
    t(2, 2) = nim.dz;
    return t;
}

} // namespace

Volume read_nifti(const std::string& path)
{
    static std::once_flag quiet;
    std::call_once(quiet, [] { nifti_set_debug_level(0); });
    std::error_code ec;
    if (!std::filesystem::is_regular_file(path, ec)) throw file_error(path, "no such file");

    // Header first: refuse absurd dimensions before libnifti allocates the voxels.
    NiftiPtr nim(nifti_image_read(path.c_str(), 0));
    if (!nim) throw file_error(path, "not a readable NIfTI file (bad magic, size or header)");
    for (int d = 4; d <= nim->dim[0] && d < 8; ++d)
        if (nim->dim[d] > 1)
            throw file_error(path, "has " + std::to_string(nim->dim[0]) + " dimensions with dim[" + std::to_string(d) +
                                       "] = " + std::to_string(nim->dim[d]) + "; only 3-D scalar volumes are supported");
    Volume v;
    v.source = path;
    v.type = scalar_type(path, nim->datatype);
    v.dims = {nim->nx, nim->dim[0] >= 2 ? nim->ny : 1, nim->dim[0] >= 3 ? nim->nz : 1};
    for (int a = 0; a < 3; ++a)
        if (v.dims[a] <= 0) throw file_error(path, "dimension " + std::to_string(a) + " is " + std::to_string(v.dims[a]));
    for (int a = 1; a <= 3; ++a)
        if (!(nim->pixdim[a] > 0.0) && nim->dim[0] >= a)
            throw file_error(path, "pixdim[" + std::to_string(a) + "] = " + std::to_string(nim->pixdim[a]) +
                                       " is not a positive voxel size");
    check_allocation(path, static_cast<std::uint64_t>(v.voxel_count()), scalar_size(v.type));

    if (nifti_image_load(nim.get()) != 0 || nim->data == nullptr)
        throw file_error(path, "truncated or unreadable voxel data");
    const std::size_t bytes = static_cast<std::size_t>(v.voxel_count()) * scalar_size(v.type);
    v.data.resize(bytes);
    std::memcpy(v.data.data(), nim->data, bytes);

    const Eigen::Matrix4d lps_from_ras = Eigen::Vector4d(-1.0, -1.0, 1.0, 1.0).asDiagonal();
    v.index_to_world = lps_from_ras * ras_index_to_world(*nim);
    // NIfTI: a zero slope means "no scaling".
    if (nim->scl_slope != 0.0) {
        v.scale_slope = nim->scl_slope;
        v.scale_intercept = nim->scl_inter;
    }
    validate(v);
    return v;
}

} // namespace vox::io
