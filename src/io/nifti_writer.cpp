#include "io/nifti_writer.hpp"

#include "core/atomic_file.hpp"
#include "core/error.hpp"

#include <nifti2_io.h>
#include <zlib.h>

#include <cmath>
#include <cstdio>
#include <cstring>
#include <memory>
#include <string>

namespace vox::io {
namespace {

short nifti_datatype(ScalarType t)
{
    switch (t) {
    case ScalarType::u8: return DT_UINT8;
    case ScalarType::i8: return DT_INT8;
    case ScalarType::u16: return DT_UINT16;
    case ScalarType::i16: return DT_INT16;
    case ScalarType::u32: return DT_UINT32;
    case ScalarType::i32: return DT_INT32;
    case ScalarType::f32: return DT_FLOAT32;
    case ScalarType::f64: return DT_FLOAT64;
    }
    return DT_UNKNOWN;
}

nifti_1_header make_header(const Volume& v, const std::string& name)
{
    nifti_1_header h;
    std::memset(&h, 0, sizeof h);
    h.sizeof_hdr = 348;
    for (int a = 0; a < 3; ++a)
        if (v.dims[static_cast<std::size_t>(a)] > 32767)
            throw file_error(name, "a NIfTI-1 file holds at most 32767 voxels an axis; this volume has " +
                                       std::to_string(v.dims[static_cast<std::size_t>(a)]));
    h.dim[0] = 3;
    for (int a = 0; a < 3; ++a) h.dim[a + 1] = static_cast<short>(v.dims[static_cast<std::size_t>(a)]);
    for (int a = 4; a < 8; ++a) h.dim[a] = 1;
    h.datatype = nifti_datatype(v.type);
    h.bitpix = static_cast<short>(8 * scalar_size(v.type));
    h.vox_offset = 352.0f;
    h.scl_slope = static_cast<float>(v.scale_slope);
    h.scl_inter = static_cast<float>(v.scale_intercept);
    h.xyzt_units = NIFTI_UNITS_MM;
    std::strncpy(h.magic, "n+1", sizeof h.magic);

    // NIfTI's world is RAS; ours LPS.
    const Eigen::Matrix4d ras = Eigen::Vector4d(-1.0, -1.0, 1.0, 1.0).asDiagonal() * v.index_to_world;
    const Eigen::Vector3d spacing = v.spacing();
    h.pixdim[0] = 1.0f;
    for (int a = 0; a < 3; ++a) h.pixdim[a + 1] = static_cast<float>(spacing[a]);
    // A volume read from NIfTI keeps its own codes and qform (a label map written back on a scan's
    // grid says what the scan said); any other gets the sform, and a qform where it can hold the
    // axes.
    const int sform_code = v.nifti ? v.nifti->sform_code : NIFTI_XFORM_SCANNER_ANAT;
    if (sform_code > 0) {
        h.sform_code = static_cast<short>(sform_code);
        for (int c = 0; c < 4; ++c) {
            h.srow_x[c] = static_cast<float>(ras(0, c));
            h.srow_y[c] = static_cast<float>(ras(1, c));
            h.srow_z[c] = static_cast<float>(ras(2, c));
        }
    }
    Eigen::Matrix4d qform = ras;
    int qform_code = 0;
    if (v.nifti) {
        qform = v.nifti->qform_ras;
        qform_code = v.nifti->qform_code;
    } else {
        // The qform holds rotations only: written when the axes are orthogonal, as readers that
        // ignore the sform then still place the voxels right.
        const Eigen::Matrix3d axes = ras.topLeftCorner<3, 3>() * spacing.cwiseInverse().asDiagonal();
        if ((axes.transpose() * axes - Eigen::Matrix3d::Identity()).cwiseAbs().maxCoeff() < 1e-6) qform_code = NIFTI_XFORM_SCANNER_ANAT;
    }
    if (qform_code > 0) {
        nifti_dmat44 m;
        for (int r = 0; r < 4; ++r)
            for (int c = 0; c < 4; ++c) m.m[r][c] = qform(r, c);
        double qb, qc, qd, qx, qy, qz, dx, dy, dz, qfac;
        nifti_dmat44_to_quatern(m, &qb, &qc, &qd, &qx, &qy, &qz, &dx, &dy, &dz, &qfac);
        h.qform_code = static_cast<short>(qform_code);
        h.quatern_b = static_cast<float>(qb);
        h.quatern_c = static_cast<float>(qc);
        h.quatern_d = static_cast<float>(qd);
        h.qoffset_x = static_cast<float>(qx);
        h.qoffset_y = static_cast<float>(qy);
        h.qoffset_z = static_cast<float>(qz);
        h.pixdim[0] = static_cast<float>(qfac);
        h.pixdim[1] = static_cast<float>(dx); // the qform's voxel sizes (the spacing, unless a kept qform says otherwise)
        h.pixdim[2] = static_cast<float>(dy);
        h.pixdim[3] = static_cast<float>(dz);
    }
    return h;
}

} // namespace

void write_nifti(const Volume& v, const std::filesystem::path& path)
{
    const std::string name = path.string();
    const bool gz = name.ends_with(".nii.gz");
    if (!gz && !name.ends_with(".nii"))
        throw file_error(name, "a NIfTI file name ends in .nii or .nii.gz");
    if (v.data.size() != static_cast<std::size_t>(v.voxel_count()) * scalar_size(v.type))
        throw file_error(name, "the volume's data does not match its dimensions");
    const nifti_1_header header = make_header(v, name);
    const char extension[4] = {0, 0, 0, 0};
    write_atomically(path, [&](const std::filesystem::path& tmp) {
        if (gz) {
            gzFile f = gzopen(tmp.c_str(), "wb6");
            if (!f) throw file_error(name, "cannot be written");
            std::unique_ptr<gzFile_s, int (*)(gzFile)> close(f, gzclose);
            bool ok = gzwrite(f, &header, sizeof header) == static_cast<int>(sizeof header) &&
                      gzwrite(f, extension, sizeof extension) == static_cast<int>(sizeof extension);
            // gzwrite takes an unsigned int length: write in pieces of at most 1 GiB.
            for (std::size_t at = 0; ok && at < v.data.size(); at += std::size_t{1} << 30) {
                const auto n = static_cast<unsigned>(std::min(v.data.size() - at, std::size_t{1} << 30));
                ok = gzwrite(f, v.data.data() + at, n) == static_cast<int>(n);
            }
            if (!ok || gzclose(close.release()) != Z_OK) throw file_error(name, "cannot be written (disk full?)");
        } else {
            std::unique_ptr<FILE, int (*)(FILE*)> f(std::fopen(tmp.c_str(), "wb"), std::fclose);
            if (!f) throw file_error(name, "cannot be written");
            const bool ok = std::fwrite(&header, sizeof header, 1, f.get()) == 1 &&
                            std::fwrite(extension, sizeof extension, 1, f.get()) == 1 &&
                            (v.data.empty() || std::fwrite(v.data.data(), v.data.size(), 1, f.get()) == 1);
            if (!ok) throw file_error(name, "cannot be written (disk full?)");
        }
    });
}

} // namespace vox::io
