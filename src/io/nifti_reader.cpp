// NIfTI-1/NIfTI-2 reader through libnifti2. The transform follows ITK (5.2 and later) and 3D Slicer:
// the sform when its code is set, else the qform when its code is set, else the voxel sizes alone
// (a set sform that is not finite gives way to a set qform, with a warning, or is refused);
// NIfTI's RAS world is converted to LPS by negating x and y. Unlike ITK we keep any shear of the
// sform instead of dropping it, so voxel centres land exactly where the file says.
//
// The raw header is checked here before libnifti sees it: libnifti prints its own diagnostics on
// stderr for some bad headers (e.g. "** ERROR: nifti_convert_n1hdr2nim: bad dim[1]") and quietly
// mends others (a NaN or zero pixdim becomes 1 mm), while a bad file must give one line of ours.

#include "core/error.hpp"
#include "core/log.hpp"
#include "core/memory_limit.hpp"
#include "io/file_bytes.hpp"
#include "io/text_parsing.hpp"
#include "io/volume_reader.hpp"

#include <nifti2_io.h>
#include <zlib.h>

#include <algorithm>
#include <array>
#include <bit>
#include <cmath>
#include <cstddef>
#include <cstdlib>
#include <cstring>
#include <limits>
#include <memory>
#include <mutex>
#include <string_view>
#include <vector>

namespace vox::io {
namespace {

struct NiftiDeleter {
    void operator()(nifti_image* nim) const { nifti_image_free(nim); }
};
using NiftiPtr = std::unique_ptr<nifti_image, NiftiDeleter>;
using detail::printable;

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
    const char* name = nifti_datatype_string(datatype); // a table look-up: prints nothing
    throw file_error(path, std::string("unsupported voxel type ") + (name ? name : "?") + " (datatype code " +
                               std::to_string(datatype) + ")");
}

/// The fields of a NIfTI-1 or NIfTI-2 header that decide whether libnifti may read it, in native
/// byte order and widened to the NIfTI-2 types.
struct RawHeader {
    int version = 1;
    std::array<std::int64_t, 8> dim{};
    std::array<double, 8> pixdim{};
    int datatype = 0;
    int bitpix = 0;
    double vox_offset = 0.0;
    std::size_t header_size = 0;
    std::uint64_t voxel_bytes = 0; ///< of the 3-D volume the dimensions describe
};

template <class T> T byte_swapped(T v)
{
    auto bytes = std::bit_cast<std::array<unsigned char, sizeof(T)>>(v);
    std::reverse(bytes.begin(), bytes.end());
    return std::bit_cast<T>(bytes);
}

/// The first bytes of the file (decompressed when it is gzip): at most `size`, fewer at its end.
std::vector<char> read_head(const std::string& path, std::size_t size)
{
    gzFile gz = gzopen(path.c_str(), "rb"); // reads plain files as they are
    if (!gz) throw file_error(path, "cannot open");
    std::vector<char> head(size);
    const int got = gzread(gz, head.data(), static_cast<unsigned>(size));
    int err = Z_OK;
    std::string msg = gzerror(gz, &err);
    gzclose(gz);
    if (got < 0 || (static_cast<std::size_t>(got) < size && err != Z_OK && err != Z_STREAM_END)) {
        if (msg.starts_with(path + ": ")) msg.erase(0, path.size() + 2);
        throw file_error(path, "corrupt or truncated gzip data (" + msg + ")");
    }
    head.resize(static_cast<std::size_t>(got));
    return head;
}

/// Reads and checks the raw header: size and magic, dimensions, voxel sizes, voxel type, data
/// offset. Throws InputError "PATH: problem" naming the field.
RawHeader check_header(const std::string& path)
{
    const std::vector<char> head = read_head(path, sizeof(nifti_2_header));
    if (head.empty()) throw file_error(path, "is empty once decompressed (gzip of no data)");
    if (head.size() < 4)
        throw file_error(path, "not a NIfTI file: " + std::to_string(head.size()) + " bytes, too short for a header");
    std::int32_t sizeof_hdr = 0;
    std::memcpy(&sizeof_hdr, head.data(), 4);
    bool swap = false;
    RawHeader raw;
    if (sizeof_hdr == 348 || byte_swapped(sizeof_hdr) == 348) {
        raw.version = 1;
        swap = sizeof_hdr != 348;
    } else if (sizeof_hdr == 540 || byte_swapped(sizeof_hdr) == 540) {
        raw.version = 2;
        swap = sizeof_hdr != 540;
    } else {
        throw file_error(path, "not a NIfTI file: sizeof_hdr is " + std::to_string(sizeof_hdr) +
                                   ", expected 348 (NIfTI-1) or 540 (NIfTI-2)");
    }
    const std::size_t need = raw.version == 1 ? sizeof(nifti_1_header) : sizeof(nifti_2_header);
    if (head.size() < need)
        throw file_error(path, "truncated: the NIfTI-" + std::to_string(raw.version) + " header needs " +
                                   std::to_string(need) + " bytes, the file has " + std::to_string(head.size()));
    const auto native = [swap](auto v) { return swap ? byte_swapped(v) : v; };

    std::string_view magic;
    if (raw.version == 1) {
        nifti_1_header h;
        std::memcpy(&h, head.data(), sizeof h);
        magic = std::string_view(head.data() + offsetof(nifti_1_header, magic), 4);
        for (int i = 0; i < 8; ++i) {
            raw.dim[static_cast<std::size_t>(i)] = native(h.dim[i]);
            raw.pixdim[static_cast<std::size_t>(i)] = native(h.pixdim[i]);
        }
        raw.datatype = native(h.datatype);
        raw.vox_offset = native(h.vox_offset);
        raw.bitpix = native(h.bitpix);
        if (magic != std::string_view("n+1\0", 4) && magic != std::string_view("ni1\0", 4)) {
            const std::string text = printable(magic.substr(0, magic.find('\0')));
            throw file_error(path, text.empty() ? std::string("has no NIfTI magic (an old ANALYZE 7.5 header?); "
                                                              "expected 'n+1'")
                                                : "wrong magic '" + text + "' for a NIfTI-1 header (expected 'n+1')");
        }
    } else {
        nifti_2_header h;
        std::memcpy(&h, head.data(), sizeof h);
        magic = std::string_view(head.data() + offsetof(nifti_2_header, magic), 8);
        for (int i = 0; i < 8; ++i) {
            raw.dim[static_cast<std::size_t>(i)] = native(h.dim[i]);
            raw.pixdim[static_cast<std::size_t>(i)] = native(h.pixdim[i]);
        }
        raw.datatype = native(h.datatype);
        raw.vox_offset = static_cast<double>(native(h.vox_offset));
        raw.bitpix = native(h.bitpix);
        if (magic != std::string_view("n+2\0\r\n\032\n", 8) && magic != std::string_view("ni2\0\r\n\032\n", 8))
            throw file_error(path, "wrong magic '" +
                                       printable(magic.substr(0, std::min<std::size_t>(4, magic.find('\0')))) +
                                       "' for a NIfTI-2 header (expected 'n+2' and the bytes 0 13 10 26 10)");
    }
    if (magic[1] != '+')
        throw file_error(path, "magic '" + printable(magic.substr(0, 3)) +
                                   "' marks the header of a .hdr/.img pair; a .nii file must have 'n+" +
                                   std::to_string(raw.version) + "' (header and voxels in one file)");

    const std::int64_t ndim = raw.dim[0];
    if (ndim < 1 || ndim > 7)
        throw file_error(path, "dim[0] = " + std::to_string(ndim) + " (the number of dimensions) is not in 1..7");
    for (std::size_t d = 1; d <= static_cast<std::size_t>(ndim); ++d)
        if (raw.dim[d] < 1)
            throw file_error(path, "dim[" + std::to_string(d) + "] = " + std::to_string(raw.dim[d]) +
                                       " (a size along an axis) is not at least 1");
    for (std::size_t d = 4; d <= static_cast<std::size_t>(ndim); ++d)
        if (raw.dim[d] > 1)
            throw file_error(path, "has " + std::to_string(ndim) + " dimensions with dim[" + std::to_string(d) +
                                       "] = " + std::to_string(raw.dim[d]) + "; only 3-D scalar volumes are supported");
    for (std::size_t a = 1; a <= std::min<std::size_t>(3, static_cast<std::size_t>(ndim)); ++a)
        if (!std::isfinite(raw.pixdim[a]) || !(raw.pixdim[a] > 0.0))
            throw file_error(path, "pixdim[" + std::to_string(a) + "] = " + detail::number_text(raw.pixdim[a]) +
                                       " is not a positive voxel size");
    const ScalarType type = scalar_type(path, raw.datatype);
    if (raw.bitpix != 8 * static_cast<int>(scalar_size(type)))
        throw file_error(path, "bitpix = " + std::to_string(raw.bitpix) + " does not match datatype " +
                                   scalar_name(type) + " (" + std::to_string(8 * scalar_size(type)) + " bits)");
    // Refuse absurd dimensions before libnifti multiplies them and allocates the voxels.
    std::uint64_t count = 1;
    for (std::size_t d = 1; d <= std::min<std::size_t>(3, static_cast<std::size_t>(ndim)); ++d) {
        const auto n = static_cast<std::uint64_t>(raw.dim[d]);
        if (count > std::numeric_limits<std::uint64_t>::max() / n)
            throw file_error(path, "its dimensions overflow 64-bit sizes");
        count *= n;
    }
    check_allocation(path, count, scalar_size(type));
    raw.voxel_bytes = count * scalar_size(type);
    raw.header_size = need;
    // The voxels follow the header and its 4-byte extension flag: at byte 352 (NIfTI-1) or 544 (NIfTI-2) or later.
    if (!std::isfinite(raw.vox_offset) || raw.vox_offset < static_cast<double>(need + 4) || raw.vox_offset > 1e15)
        throw file_error(path, "vox_offset = " + detail::number_text(raw.vox_offset) +
                                   " does not point past the header (at least " + std::to_string(need + 4) + ")");
    return raw;
}

/// `bytes` bytes of the file (decompressed when it is gzip) from `offset` on, inflated once. A
/// file too short for them is refused with what it holds: libnifti would only say that it cannot
/// load them, and for a gzip file whose vox_offset points past its data it read from the wrong place
/// without complaint. libnifti's loader is not used for the voxels at all: it looks for the image
/// file by name and, when "scan.nii" lies beside the "scan.nii.gz" asked for, reads the other one's
/// (found by fuzzing).
std::vector<std::byte> read_voxels(const std::string& path, std::uint64_t offset, std::uint64_t bytes)
{
    gzFile gz = gzopen(path.c_str(), "rb"); // reads plain files as they are
    if (!gz) throw file_error(path, "cannot open");
    std::vector<std::byte> data(bytes);
    std::vector<char> skip(1 << 16);
    bool ok = true;
    for (std::uint64_t skipped = 0; ok && skipped < offset;) { // gzseek would do the same, less clearly
        const auto n = static_cast<unsigned>(std::min<std::uint64_t>(skip.size(), offset - skipped));
        ok = gzread(gz, skip.data(), n) == static_cast<int>(n);
        skipped += n;
    }
    std::uint64_t done = 0;
    while (ok && done < bytes) {
        const auto n = static_cast<unsigned>(std::min<std::uint64_t>(std::uint64_t{1} << 30, bytes - done));
        const int got = gzread(gz, data.data() + done, n);
        ok = got == static_cast<int>(n);
        done += got > 0 ? static_cast<std::uint64_t>(got) : 0;
    }
    gzclose(gz);
    if (!ok)
        throw file_error(path, "truncated: holds " + std::to_string(done) + " bytes of voxel data after vox_offset " +
                                   std::to_string(offset) + ", the header's dimensions need " + std::to_string(bytes));
    return data;
}

Eigen::Matrix4d to_eigen(const nifti_dmat44& m)
{
    Eigen::Matrix4d t;
    for (int r = 0; r < 4; ++r)
        for (int c = 0; c < 4; ++c) t(r, c) = m.m[r][c];
    return t;
}

Eigen::Matrix4d ras_index_to_world(const nifti_image& nim, const RawHeader& raw, const std::string& path)
{
    // A transform with a NaN or an infinity places nothing; the other one, when the file has it,
    // is what a reader that ignored the broken one would use (said, since it may differ).
    const Eigen::Matrix4d sform = to_eigen(nim.sto_xyz), qform = to_eigen(nim.qto_xyz);
    const bool sform_ok = sform.allFinite(), qform_ok = qform.allFinite();
    if (nim.sform_code > 0 && sform_ok) return sform;
    if (nim.sform_code > 0 && !(nim.qform_code > 0 && qform_ok))
        throw file_error(path, "its sform (the transform that places its voxels) is not finite (a NaN or an infinity), and it has no "
                               "usable qform to fall back on");
    if (nim.sform_code > 0) {
        log::warn("{}: its sform is not finite (a NaN or an infinity); placed by its qform instead", path);
        return qform;
    }
    if (nim.qform_code > 0 && !qform_ok)
        throw file_error(path, "its qform (the transform that places its voxels) is not finite (a NaN or an infinity), and it has no sform");
    if (nim.qform_code > 0) return qform;
    // The voxel sizes of the header (checked positive along the image's axes); an axis the image
    // does not have (a 2-D image's third) gets 1 mm when its pixdim is unset.
    Eigen::Matrix4d t = Eigen::Matrix4d::Identity();
    for (std::size_t a = 1; a <= 3; ++a) {
        const double d = raw.pixdim[a];
        const bool used = static_cast<std::int64_t>(a) <= raw.dim[0];
        t(static_cast<Eigen::Index>(a - 1), static_cast<Eigen::Index>(a - 1)) =
            used || (std::isfinite(d) && d > 0.0) ? d : 1.0;
    }
    return t;
}

} // namespace

Volume read_nifti(const std::string& path)
{
    static std::once_flag quiet;
    std::call_once(quiet, [] { nifti_set_debug_level(0); });
    check_input_file(path);
    const RawHeader raw = check_header(path);

    NiftiPtr nim(nifti_image_read(path.c_str(), 0)); // the header only
    if (!nim) throw file_error(path, "not a readable NIfTI file (libnifti refuses its header)");
    Volume v;
    v.source = path;
    v.type = scalar_type(path, nim->datatype);
    v.dims = {nim->nx, nim->dim[0] >= 2 ? nim->ny : 1, nim->dim[0] >= 3 ? nim->nz : 1};
    for (int a = 0; a < 3; ++a)
        if (v.dims[a] <= 0)
            throw file_error(path, "dimension " + std::to_string(a) + " is " + std::to_string(v.dims[a]));
    check_allocation(path, static_cast<std::uint64_t>(v.voxel_count()), scalar_size(v.type));

    v.data = read_voxels(path, static_cast<std::uint64_t>(raw.vox_offset), static_cast<std::uint64_t>(v.voxel_count()) * scalar_size(v.type));
    if (nim->byteorder != nifti_short_order()) swap_bytes(v);

    const Eigen::Matrix4d lps_from_ras = Eigen::Vector4d(-1.0, -1.0, 1.0, 1.0).asDiagonal();
    v.index_to_world = lps_from_ras * ras_index_to_world(*nim, raw, path);
    // Its own codes and qform, for a label map written back on its grid (a qform that is not
    // finite is not kept).
    NiftiTransforms kept;
    kept.sform_code = nim->sform_code;
    kept.qform_ras = to_eigen(nim->qto_xyz);
    kept.qform_code = kept.qform_ras.allFinite() ? nim->qform_code : 0;
    if (kept.qform_code == 0) kept.qform_ras.setIdentity();
    v.nifti = kept;
    // NIfTI: a zero slope means "no scaling".
    if (nim->scl_slope != 0.0) {
        v.scale_slope = nim->scl_slope;
        v.scale_intercept = nim->scl_inter;
    }
    validate(v);
    return v;
}

} // namespace vox::io
