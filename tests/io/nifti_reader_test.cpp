#include "io/volume_reader.hpp"

#include "core/error.hpp"
#include "io/test_volume_writers.hpp"
#include "test_support.hpp"

#include <gtest/gtest.h>
#include <nifti2_io.h>

#include <algorithm>
#include <array>
#include <bit>
#include <cmath>
#include <cstddef>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <functional>
#include <iterator>
#include <limits>
#include <utility>

namespace fs = std::filesystem;
using namespace vox::io;
using vox::test::world;

namespace {

/// A 3 x 2 x 2 int16 NIfTI-1 file written by libnifti2 itself; `setup` fills the header fields.
std::string write_nifti_file(const std::string& name, const std::function<void(nifti_image&)>& setup)
{
    const int64_t dims[8] = {3, 3, 2, 2, 1, 1, 1, 1};
    nifti_image* nim = nifti_make_new_nim(dims, DT_INT16, 1);
    auto* data = static_cast<std::int16_t*>(nim->data);
    for (int n = 0; n < 12; ++n) data[n] = static_cast<std::int16_t>(n * 10 - 50);
    nim->nifti_type = NIFTI_FTYPE_NIFTI1_1;
    setup(*nim);
    const std::string path = (fs::path(::testing::TempDir()) / name).string();
    nifti_set_filenames(nim, path.c_str(), 0, 1);
    nifti_image_write(nim);
    nifti_image_free(nim);
    return path;
}

} // namespace

TEST(NiftiReader, QformRotationIsConvertedFromRasToLps)
{
    // qform: 90 degrees about z (quaternion a = cos 45, d = sin 45), spacing 2 3 4, offset (10 20 30).
    const std::string path = write_nifti_file("qform.nii", [](nifti_image& nim) {
        nim.pixdim[1] = nim.dx = 2;
        nim.pixdim[2] = nim.dy = 3;
        nim.pixdim[3] = nim.dz = 4;
        nim.qform_code = NIFTI_XFORM_SCANNER_ANAT;
        nim.sform_code = 0;
        nim.quatern_b = 0;
        nim.quatern_c = 0;
        nim.quatern_d = std::sqrt(0.5);
        nim.qoffset_x = 10;
        nim.qoffset_y = 20;
        nim.qoffset_z = 30;
        nim.qfac = 1;
    });
    const Volume v = read_volume(path);
    EXPECT_EQ(v.dims, (std::array<std::int64_t, 3>{3, 2, 2}));
    // In RAS, index axis i points along +y: voxel (1,0,0) is at (10, 22, 30); LPS negates x and y.
    EXPECT_TRUE(world(v, 0, 0, 0).isApprox(Eigen::Vector3d(-10, -20, 30), 1e-6));
    EXPECT_TRUE(world(v, 1, 0, 0).isApprox(Eigen::Vector3d(-10, -22, 30), 1e-6));
    EXPECT_TRUE(world(v, 0, 1, 0).isApprox(Eigen::Vector3d(-7, -20, 30), 1e-6));
    EXPECT_TRUE(world(v, 0, 0, 1).isApprox(Eigen::Vector3d(-10, -20, 34), 1e-6));
    EXPECT_EQ(v.stored(0), -50.0);
    EXPECT_EQ(v.stored(11), 60.0);
}

TEST(NiftiReader, SformTakesPrecedenceAndKeepsShear)
{
    const std::string path = write_nifti_file("sform.nii.gz", [](nifti_image& nim) {
        nim.qform_code = NIFTI_XFORM_SCANNER_ANAT; // identity qform, overridden by the sform
        nim.sform_code = NIFTI_XFORM_ALIGNED_ANAT;
        const double s[3][4] = {{1.5, 0.25, 0, -5}, {0, 2, 0, 7}, {0, 0, 0.5, 1}};
        for (int r = 0; r < 3; ++r)
            for (int c = 0; c < 4; ++c) nim.sto_xyz.m[r][c] = s[r][c];
    });
    const Volume v = read_volume(path);
    EXPECT_TRUE(world(v, 0, 0, 0).isApprox(Eigen::Vector3d(5, -7, 1), 1e-6));
    EXPECT_TRUE(world(v, 2, 1, 1).isApprox(Eigen::Vector3d(-(3 + 0.25 - 5), -(2 + 7), 1.5), 1e-6));
}

TEST(NiftiReader, SlopeAndInterceptScaleValues)
{
    const std::string path = write_nifti_file("scaled.nii", [](nifti_image& nim) {
        nim.scl_slope = 2;
        nim.scl_inter = -1024;
    });
    const Volume v = read_volume(path);
    EXPECT_EQ(v.stored(1), -40.0);
    EXPECT_EQ(v.scaled(1), -1104.0);
}

TEST(NiftiReader, TheGzipFileAskedForIsReadEvenWithAPlainOneBesideIt)
{
    // Fuzzing found libnifti reading the voxels of "twin.nii" when asked for "twin.nii.gz".
    const std::string gz = write_nifti_file("twin.nii.gz", [](nifti_image& nim) { nim.scl_slope = 1; });
    const std::string plain = write_nifti_file("twin.nii", [](nifti_image& nim) {
        auto* data = static_cast<std::int16_t*>(nim.data);
        for (int n = 0; n < 12; ++n) data[n] = 7;
    });
    const Volume v = read_volume(gz);
    for (int n = 0; n < 12; ++n) EXPECT_EQ(v.stored(n), n * 10 - 50) << n;
    EXPECT_EQ(read_volume(plain).stored(3), 7.0);
}

TEST(NiftiReader, MissingFileAndGarbageAreInputErrors)
{
    EXPECT_THROW((void)read_volume("/nonexistent/scan.nii"), vox::InputError);
    const std::string junk = (fs::path(::testing::TempDir()) / "junk.nii").string();
    std::ofstream(junk) << "this is not a nifti header";
    try {
        (void)read_volume(junk);
        FAIL();
    } catch (const vox::InputError& e) {
        EXPECT_EQ(std::string(e.what()).rfind(junk + ": ", 0), 0u) << e.what();
    }
}

namespace {

/// The fields of a hand-made NIfTI-1 header: a 2 x 2 x 2 int16 volume by default, no sform or
/// qform, voxels at byte 352.
struct N1Fields {
    std::int32_t sizeof_hdr = 348;
    std::array<std::int16_t, 8> dim{3, 2, 2, 2, 1, 1, 1, 1};
    std::int16_t datatype = DT_INT16;
    std::int16_t bitpix = 16;
    std::array<float, 8> pixdim{1, 1, 1, 1, 0, 0, 0, 0};
    float vox_offset = 352;
    std::string magic{"n+1\0", 4};
    bool big_endian = false;
};

/// Appends `value` at `offset` of `out`, in the header's byte order.
template <class T> void put_at(std::string& out, std::size_t offset, T value, bool big_endian)
{
    char bytes[sizeof(T)];
    std::memcpy(bytes, &value, sizeof(T));
    if (big_endian != (std::endian::native == std::endian::big)) std::reverse(bytes, bytes + sizeof(T));
    std::memcpy(out.data() + offset, bytes, sizeof(T));
}

/// The header (348 bytes), the 4-byte extension flag and `data_bytes` zero bytes of voxels.
std::string n1_file(const N1Fields& f, std::size_t data_bytes = 16)
{
    std::string s(352 + data_bytes, '\0');
    put_at(s, 0, f.sizeof_hdr, f.big_endian);
    for (std::size_t i = 0; i < 8; ++i) put_at(s, 40 + 2 * i, f.dim[i], f.big_endian);
    put_at(s, 70, f.datatype, f.big_endian);
    put_at(s, 72, f.bitpix, f.big_endian);
    for (std::size_t i = 0; i < 8; ++i) put_at(s, 76 + 4 * i, f.pixdim[i], f.big_endian);
    put_at(s, 108, f.vox_offset, f.big_endian);
    put_at(s, 112, 1.0f, f.big_endian); // scl_slope
    s.replace(344, 4, f.magic);
    return s;
}

std::string temp_path(const std::string& name) { return (fs::path(::testing::TempDir()) / name).string(); }

std::string write_bytes(const std::string& name, const std::string& bytes)
{
    const std::string path = temp_path(name);
    std::ofstream(path, std::ios::binary) << bytes;
    return path;
}

/// Expects read_volume(path) to throw one line "PATH: ..." containing `problem`, and nothing
/// (libnifti's diagnostics in particular) to reach stdout or stderr.
void expect_one_line_refusal(const std::string& path, const std::string& problem)
{
    SCOPED_TRACE(path);
    ::testing::internal::CaptureStderr();
    ::testing::internal::CaptureStdout();
    std::string message;
    try {
        (void)read_volume(path);
    } catch (const vox::InputError& e) {
        message = e.what();
    }
    const std::string out = ::testing::internal::GetCapturedStdout();
    const std::string err = ::testing::internal::GetCapturedStderr();
    ASSERT_FALSE(message.empty()) << "no InputError";
    EXPECT_EQ(message.rfind(path + ": ", 0), 0u) << message;
    EXPECT_NE(message.find(problem), std::string::npos) << message;
    EXPECT_EQ(message.find('\n'), std::string::npos) << message;
    EXPECT_EQ(out, "");
    EXPECT_EQ(err, "");
}

} // namespace

TEST(NiftiReader, HandMadeHeaderReads)
{
    // The builder itself makes a valid file, in either byte order: the refusals below are the field's.
    for (const bool big : {false, true}) {
        N1Fields f;
        f.big_endian = big;
        f.pixdim = {1, 0.5, 2, 3, 0, 0, 0, 0};
        std::string bytes = n1_file(f);
        bytes[352 + (big ? 1 : 0)] = 7; // voxel 0 = 7
        const Volume v = read_volume(write_bytes(big ? "big.nii" : "little.nii", bytes));
        EXPECT_EQ(v.dims, (std::array<std::int64_t, 3>{2, 2, 2}));
        EXPECT_EQ(v.stored(0), 7.0);
        EXPECT_TRUE(v.spacing().isApprox(Eigen::Vector3d(0.5, 2, 3)));
    }
    // A 2-D image may leave pixdim[3] unset.
    N1Fields flat;
    flat.dim = {2, 2, 2, 1, 1, 1, 1, 1};
    flat.pixdim = {1, 0.5, 2, 0, 0, 0, 0, 0};
    const Volume v = read_volume(write_bytes("flat.nii", n1_file(flat, 8)));
    EXPECT_EQ(v.dims, (std::array<std::int64_t, 3>{2, 2, 1}));
    EXPECT_TRUE(v.spacing().isApprox(Eigen::Vector3d(0.5, 2, 1)));
}

TEST(NiftiReader, BadDimensionsAreOneLineOfOurs)
{
    // libnifti printed "** ERROR: nifti_convert_n1hdr2nim: bad dim[1]" before our own line.
    N1Fields f;
    f.dim[1] = 0;
    expect_one_line_refusal(write_bytes("dim1_zero.nii", n1_file(f)), "dim[1] = 0");
    expect_one_line_refusal(write_bytes("dim1_zero.nii.gz", vox::test::gzip(n1_file(f))), "dim[1] = 0");
    f = {};
    f.dim[3] = -4;
    expect_one_line_refusal(write_bytes("dim3_negative.nii", n1_file(f)), "dim[3] = -4");
    f = {};
    f.dim[0] = 0;
    expect_one_line_refusal(write_bytes("dim0_zero.nii", n1_file(f)), "dim[0] = 0");
    f.dim[0] = 8;
    expect_one_line_refusal(write_bytes("dim0_eight.nii", n1_file(f)), "dim[0] = 8");
    f = {};
    f.dim = {4, 2, 2, 2, 3, 1, 1, 1};
    expect_one_line_refusal(write_bytes("four_d.nii", n1_file(f, 48)), "dim[4] = 3; only 3-D scalar volumes");
    f = {};
    f.dim = {3, 30000, 30000, 30000, 1, 1, 1, 1};
    expect_one_line_refusal(write_bytes("huge.nii", n1_file(f)), "memory limit");
}

TEST(NiftiReader, BadVoxelSizesAreRefused)
{
    // A NaN pixdim without sform or qform became 1 mm silently.
    const std::pair<float, const char*> cases[] = {{std::numeric_limits<float>::quiet_NaN(), "nan"},
                                                   {0.0f, "0"},
                                                   {-1.0f, "-1"},
                                                   {std::numeric_limits<float>::infinity(), "inf"}};
    for (const auto& [bad, text] : cases) {
        N1Fields f;
        f.pixdim[2] = bad;
        expect_one_line_refusal(write_bytes("bad_pixdim.nii", n1_file(f)),
                                std::string("pixdim[2] = ") + text + " is not a positive voxel size");
    }
    N1Fields f;
    f.pixdim[1] = std::numeric_limits<float>::quiet_NaN();
    expect_one_line_refusal(write_bytes("nan_pixdim.nii.gz", vox::test::gzip(n1_file(f))), "pixdim[1] = nan");
}

TEST(NiftiReader, BadMagicSizeAndTypeAreRefused)
{
    N1Fields f;
    f.magic = std::string("n+2\0", 4);
    expect_one_line_refusal(write_bytes("magic_n2.nii", n1_file(f)), "wrong magic 'n+2'");
    f.magic = "abcd";
    expect_one_line_refusal(write_bytes("magic_abcd.nii", n1_file(f)), "wrong magic 'abcd'");
    f.magic = std::string(4, '\0');
    expect_one_line_refusal(write_bytes("analyze.nii", n1_file(f)), "has no NIfTI magic");
    f.magic = std::string("ni1\0", 4);
    expect_one_line_refusal(write_bytes("pair_magic.nii", n1_file(f)),
                            "magic 'ni1' marks the header of a .hdr/.img pair");
    f = {};
    f.sizeof_hdr = 349;
    expect_one_line_refusal(write_bytes("sizeof.nii", n1_file(f)), "sizeof_hdr is 349");
    f = {};
    f.datatype = DT_COMPLEX64;
    f.bitpix = 64;
    expect_one_line_refusal(write_bytes("complex.nii", n1_file(f, 64)), "unsupported voxel type");
    f = {};
    f.bitpix = 8;
    expect_one_line_refusal(write_bytes("bitpix.nii", n1_file(f)), "bitpix = 8 does not match datatype int16");
    f = {};
    f.vox_offset = 100;
    expect_one_line_refusal(write_bytes("vox_offset.nii", n1_file(f)), "vox_offset = 100");
    f.vox_offset = std::numeric_limits<float>::quiet_NaN();
    expect_one_line_refusal(write_bytes("vox_offset_nan.nii", n1_file(f)), "vox_offset = nan");
}

TEST(NiftiReader, TruncatedAndEmptyFilesAreRefused)
{
    const std::string whole = n1_file(N1Fields{});
    expect_one_line_refusal(write_bytes("short_header.nii", whole.substr(0, 200)),
                            "truncated: the NIfTI-1 header needs 348 bytes, the file has 200");
    expect_one_line_refusal(write_bytes("short_header.nii.gz", vox::test::gzip(whole.substr(0, 200))),
                            "truncated: the NIfTI-1 header needs 348 bytes");
    expect_one_line_refusal(write_bytes("short_data.nii", whole.substr(0, 360)),
                            "truncated: holds 8 bytes of voxel data after vox_offset 352");
    expect_one_line_refusal(write_bytes("tiny.nii", "ab"), "too short for a header");
    expect_one_line_refusal(write_bytes("empty.nii", ""), ": is empty");
    expect_one_line_refusal(write_bytes("empty.nii.gz", ""), ": is empty");
    expect_one_line_refusal(write_bytes("empty_stream.nii.gz", vox::test::gzip("")), "is empty once decompressed");
    const std::string zipped = vox::test::gzip(whole);
    const std::string cut = write_bytes("cut.nii.gz", zipped.substr(0, zipped.size() / 2));
    expect_one_line_refusal(cut, "truncated");
    // zlib's own message starts with the file name; ours already does, once.
    const std::string message = vox::test::error_of([&] { (void)read_volume(cut); });
    EXPECT_EQ(message.find(cut, 1), std::string::npos) << message;
}

TEST(NiftiReader, Nifti2HeadersAreCheckedToo)
{
    // A hand-made NIfTI-2 file (libnifti's writer needs coaxing into NIfTI-2) of 3 x 2 x 2 int16:
    // libnifti reads it; broken copies are refused by our check.
    nifti_2_header h{};
    h.sizeof_hdr = 540;
    std::memcpy(h.magic, "n+2\0\r\n\032\n", 8);
    h.datatype = DT_INT16;
    h.bitpix = 16;
    const std::int64_t dims[8] = {3, 3, 2, 2, 1, 1, 1, 1};
    const double pixdim[8] = {1, 0.5, 2, 3, 0, 0, 0, 0};
    std::memcpy(h.dim, dims, sizeof dims);
    std::memcpy(h.pixdim, pixdim, sizeof pixdim);
    h.vox_offset = 544;
    h.scl_slope = 1;
    std::string bytes(reinterpret_cast<const char*>(&h), sizeof h);
    bytes += std::string(4, '\0');
    for (int n = 0; n < 12; ++n) {
        const auto value = static_cast<std::int16_t>(n * 10 - 50);
        bytes.append(reinterpret_cast<const char*>(&value), 2);
    }
    const Volume v = read_volume(write_bytes("n2.nii", bytes));
    EXPECT_EQ(v.dims, (std::array<std::int64_t, 3>{3, 2, 2}));
    EXPECT_EQ(v.stored(11), 60.0);
    EXPECT_TRUE(v.spacing().isApprox(Eigen::Vector3d(0.5, 2, 3)));

    const auto with = [&](std::size_t offset, const auto &value) {
        std::string copy = bytes;
        std::memcpy(copy.data() + offset, &value, sizeof value);
        return copy;
    };
    expect_one_line_refusal(
        write_bytes("n2_dim2_zero.nii", with(offsetof(nifti_2_header, dim) + 2 * 8, std::int64_t{0})), "dim[2] = 0");
    expect_one_line_refusal(write_bytes("n2_nan_pixdim.nii", with(offsetof(nifti_2_header, pixdim) + 3 * 8,
                                                                  std::numeric_limits<double>::quiet_NaN())),
                            "pixdim[3] = nan");
    expect_one_line_refusal(write_bytes("n2_magic.nii", with(offsetof(nifti_2_header, magic), 'x')),
                            "wrong magic 'x+2'");
    expect_one_line_refusal(write_bytes("n2_short.nii", bytes.substr(0, 400)),
                            "truncated: the NIfTI-2 header needs 540 bytes, the file has 400");
}

TEST(NiftiReader, FolderIsNotAFile)
{
    const std::string folder = temp_path("folder.nii");
    fs::create_directories(folder);
    expect_one_line_refusal(folder, "is a folder, not a file");
}
