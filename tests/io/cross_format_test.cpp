// One volume through every format: written by the test writers (NIfTI through libnifti2's own
// writer), read back through read_volume, it must give the same voxels, dimensions and transform.
// Also: hand-made big-endian files, and the malformed volume files of tests/data/bad.

#include "core/error.hpp"
#include "io/object_import.hpp"
#include "io/test_volume_writers.hpp"
#include "io/volume_reader.hpp"
#include "test_support.hpp"

#include <Eigen/Geometry>
#include <gtest/gtest.h>

#include <bit>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>

namespace vox::io {
namespace {

namespace fs = std::filesystem;

/// A 7x5x3 volume of `type` with distinct values (negative ones for signed types), spacing
/// (0.5, 0.75, 1.25) mm and origin (-10, 20, 5) mm, oriented by `direction`.
Volume make_volume(ScalarType type, const Eigen::Matrix3d& direction)
{
    Volume v;
    v.dims = {7, 5, 3};
    v.type = type;
    v.index_to_world = make_index_to_world(Eigen::Vector3d(0.5, 0.75, 1.25), direction, Eigen::Vector3d(-10, 20, 5));
    const std::int64_t n = v.voxel_count();
    v.data.resize(static_cast<std::size_t>(n) * scalar_size(type));
    for (std::int64_t i = 0; i < n; ++i) {
        std::byte* out = v.data.data() + i * static_cast<std::int64_t>(scalar_size(type));
        auto put = [&](auto value) { std::memcpy(out, &value, sizeof(value)); };
        switch (type) {
        case ScalarType::u8: put(static_cast<std::uint8_t>(i * 2 + 1)); break;
        case ScalarType::i8: put(static_cast<std::int8_t>(i - 60)); break;
        case ScalarType::u16: put(static_cast<std::uint16_t>(i * 601 + 7)); break;
        case ScalarType::i16: put(static_cast<std::int16_t>(i * 37 - 2000)); break;
        case ScalarType::u32: put(static_cast<std::uint32_t>(i * 40000003u + 11u)); break;
        case ScalarType::i32: put(static_cast<std::int32_t>((i - 50) * 20000003)); break;
        case ScalarType::f32: put(static_cast<float>(i) * -0.375f + 3.0f); break;
        case ScalarType::f64: put(static_cast<double>(i) / 3.0 - 17.0); break;
        }
    }
    return v;
}

/// A proper rotation (det +1) that is not the identity and whose entries are exact in float32,
/// so NIfTI-1's float fields carry it without rounding: index i -> +y, j -> -z, k -> -x.
Eigen::Matrix3d permuting_rotation()
{
    Eigen::Matrix3d d;
    d << 0, 0, -1, //
        1, 0, 0,   //
        0, -1, 0;
    return d;
}

/// A generic rotation: its entries are not exact in float32.
Eigen::Matrix3d oblique_rotation()
{
    return Eigen::AngleAxisd(0.4, Eigen::Vector3d(1, -2, 0.7).normalized()).toRotationMatrix();
}

enum class Format { nii, nii_gz, mhd_raw, mhd_zraw, mha_raw, mha_zlib, nrrd_raw, nrrd_gzip, nhdr_raw, nhdr_gzip };

struct FormatInfo {
    const char* file;
    bool float32_geometry; ///< the format stores the transform as float32 (NIfTI-1)
};

FormatInfo format_info(Format f)
{
    switch (f) {
    case Format::nii: return {"volume.nii", true};
    case Format::nii_gz: return {"volume.nii.gz", true};
    case Format::mhd_raw: return {"volume.mhd", false};
    case Format::mhd_zraw: return {"zipped.mhd", false};
    case Format::mha_raw: return {"volume.mha", false};
    case Format::mha_zlib: return {"zipped.mha", false};
    case Format::nrrd_raw: return {"volume.nrrd", false};
    case Format::nrrd_gzip: return {"zipped.nrrd", false};
    case Format::nhdr_raw: return {"volume.nhdr", false};
    case Format::nhdr_gzip: return {"zipped.nhdr", false};
    }
    return {"", false};
}

void write(const Volume& v, Format f, const std::string& path)
{
    switch (f) {
    case Format::nii:
    case Format::nii_gz: test::write_nifti(v, path); break;
    case Format::mhd_raw:
    case Format::mha_raw: test::write_metaimage(v, path, false); break;
    case Format::mhd_zraw:
    case Format::mha_zlib: test::write_metaimage(v, path, true); break;
    case Format::nrrd_raw:
    case Format::nhdr_raw: test::write_nrrd(v, path, "raw"); break;
    case Format::nrrd_gzip:
    case Format::nhdr_gzip: test::write_nrrd(v, path, "gzip"); break;
    }
}

void expect_same(const Volume& expected, const Volume& got, double transform_tolerance)
{
    EXPECT_EQ(got.dims, expected.dims);
    EXPECT_EQ(got.type, expected.type) << scalar_name(got.type) << " vs " << scalar_name(expected.type);
    EXPECT_EQ(got.scale_slope, 1.0);
    EXPECT_EQ(got.scale_intercept, 0.0);
    EXPECT_TRUE(got.data == expected.data) << "voxel values differ";
    EXPECT_LE((got.index_to_world - expected.index_to_world).cwiseAbs().maxCoeff(), transform_tolerance)
        << "read:\n"
        << got.index_to_world << "\nwritten:\n"
        << expected.index_to_world;
}

class CrossFormat : public ::testing::TestWithParam<std::tuple<Format, ScalarType>> {};

TEST_P(CrossFormat, ReadsBackWhatWasWritten)
{
    const auto [format, type] = GetParam();
    const test::ScratchDir dir;
    const Volume v = make_volume(type, permuting_rotation());
    const std::string path = dir.path(format_info(format).file);
    write(v, format, path);
    const Volume r = read_volume(path);
    EXPECT_EQ(r.source, path);
    expect_same(v, r, 1e-9);
}

INSTANTIATE_TEST_SUITE_P(
    AllFormatsAndTypes, CrossFormat,
    ::testing::Combine(::testing::Values(Format::nii, Format::nii_gz, Format::mhd_raw, Format::mhd_zraw,
                                         Format::mha_raw, Format::mha_zlib, Format::nrrd_raw, Format::nrrd_gzip,
                                         Format::nhdr_raw, Format::nhdr_gzip),
                       ::testing::Values(ScalarType::i16, ScalarType::u8, ScalarType::i8, ScalarType::u16,
                                         ScalarType::u32, ScalarType::i32, ScalarType::f32, ScalarType::f64)),
    [](const auto& param) {
        std::string name = format_info(std::get<0>(param.param)).file;
        for (char& c : name)
            if (c == '.') c = '_';
        return name + "_" + scalar_name(std::get<1>(param.param));
    });

TEST(CrossFormatGeometry, ObliqueRotationAgreesAcrossFormats)
{
    // MetaImage and NRRD carry doubles in text: exact to 1e-9. NIfTI-1 stores the sform as float32,
    // so it can only agree to float precision (about 1e-7 relative on 20 mm coordinates).
    const test::ScratchDir dir;
    const Volume v = make_volume(ScalarType::i16, oblique_rotation());
    for (const Format f :
         {Format::nii, Format::nii_gz, Format::mhd_raw, Format::mha_zlib, Format::nrrd_raw, Format::nrrd_gzip}) {
        SCOPED_TRACE(format_info(f).file);
        write(v, f, dir.path(format_info(f).file));
        expect_same(v, read_volume(dir.path(format_info(f).file)), format_info(f).float32_geometry ? 1e-5 : 1e-9);
    }
}

TEST(CrossFormatGeometry, InrAxisAlignedVolume)
{
    const test::ScratchDir dir;
    for (const ScalarType type : {ScalarType::i16, ScalarType::u8, ScalarType::u16, ScalarType::f32, ScalarType::f64}) {
        SCOPED_TRACE(scalar_name(type));
        const Volume v = make_volume(type, Eigen::Matrix3d::Identity());
        test::write_inr(v, dir.path("volume.inr"));
        expect_same(v, read_volume(dir.path("volume.inr")), 1e-9);
        // The same volume through a format with a full transform lands on the same voxels.
        test::write_nrrd(v, dir.path("volume.nrrd"), "raw");
        expect_same(read_volume(dir.path("volume.inr")), read_volume(dir.path("volume.nrrd")), 1e-9);
    }
}

/// The i16 test volume's voxel bytes, most significant byte first.
std::string big_endian_i16(const Volume& v)
{
    std::string out(reinterpret_cast<const char*>(v.data.data()), v.data.size());
    if (std::endian::native == std::endian::little)
        for (std::size_t i = 0; i + 1 < out.size(); i += 2) std::swap(out[i], out[i + 1]);
    return out;
}

TEST(CrossFormatByteOrder, BigEndianMetaImageAndNrrdMatchLittleEndian)
{
    const test::ScratchDir dir;
    const Volume v = make_volume(ScalarType::i16, Eigen::Matrix3d::Identity());
    test::write_metaimage(v, dir.path("little.mha"), false);
    const Volume little = read_volume(dir.path("little.mha"));

    std::ofstream(dir.path("big.mha"), std::ios::binary)
        << "ObjectType = Image\nNDims = 3\nBinaryData = True\nBinaryDataByteOrderMSB = True\n"
           "CompressedData = False\nTransformMatrix = 1 0 0 0 1 0 0 0 1\nOffset = -10 20 5\n"
           "ElementSpacing = 0.5 0.75 1.25\nDimSize = 7 5 3\nElementType = MET_SHORT\nElementDataFile = LOCAL\n"
        << big_endian_i16(v);
    expect_same(little, read_volume(dir.path("big.mha")), 0.0);

    std::ofstream(dir.path("big.nrrd"), std::ios::binary)
        << "NRRD0004\ntype: short\ndimension: 3\nspace: left-posterior-superior\nsizes: 7 5 3\n"
           "space directions: (0.5,0,0) (0,0.75,0) (0,0,1.25)\nendian: big\nencoding: raw\n"
           "space origin: (-10,20,5)\n\n"
        << big_endian_i16(v);
    expect_same(little, read_volume(dir.path("big.nrrd")), 0.0);
}

TEST(CrossFormatGeometry, NrrdInRasSpaceMatchesTheLpsNifti)
{
    // The same physical volume described in RAS (NRRD) and through NIfTI (RAS on disk, converted
    // by its reader): both must give the LPS transform with x and y negated from the RAS file.
    const test::ScratchDir dir;
    const Volume v = make_volume(ScalarType::i16, permuting_rotation());
    const Eigen::Matrix4d ras = Eigen::Vector4d(-1, -1, 1, 1).asDiagonal() * v.index_to_world;
    std::ostringstream header;
    header.precision(17);
    header << "NRRD0004\ntype: short\ndimension: 3\nspace: right-anterior-superior\nsizes: 7 5 3\nspace directions:";
    for (int a = 0; a < 3; ++a) header << " (" << ras(0, a) << ',' << ras(1, a) << ',' << ras(2, a) << ')';
    header << "\nendian: little\nencoding: raw\nspace origin: (" << ras(0, 3) << ',' << ras(1, 3) << ',' << ras(2, 3)
           << ")\n\n";
    std::ofstream(dir.path("ras.nrrd"), std::ios::binary)
        << header.str() << std::string(reinterpret_cast<const char*>(v.data.data()), v.data.size());
    test::write_nifti(v, dir.path("volume.nii"));
    expect_same(v, read_volume(dir.path("ras.nrrd")), 1e-12);
    expect_same(read_volume(dir.path("ras.nrrd")), read_volume(dir.path("volume.nii")), 1e-9);
}

TEST(CrossFormatMalformed, EveryBadVolumeFileIsRefusedNamingIt)
{
    // What each file of ours must be refused for (tests/data/bad/README.md says why), imported as
    // `voxsculpt import FILE` does: read, then every non-zero voxel kept as its label.
    const std::map<std::string, std::string> expected = {
        {"dicom_bad_orientation.dcm", "ImageOrientationPatient 1\\0\\0\\1\\0\\0 is not two orthogonal unit vectors"},
        {"dicom_colour.dcm", "has 3 samples a pixel (a colour image)"},
        {"dicom_empty.dcm", ": is empty"},
        {"dicom_truncated.dcm", "GDCM's reader crashed on it (SIGABRT; the file is corrupt or truncated)"},
        {"mha_bad_element_type.mha", "unsupported ElementType"},
        {"mha_compressed_corrupt.mha", "corrupt compressed data"},
        {"mha_empty.mha", ": is empty"},
        {"mha_multichannel.mha", "single-channel"},
        {"mha_no_datafile_line.mha", "no 'ElementDataFile' line"},
        {"mha_truncated.mha", "truncated"},
        {"mhd_dimsize_count.mhd", "'DimSize' has 2 values, expected 3"},
        {"mhd_huge_dims.mhd", "memory limit"},
        {"mhd_list_datafile.mhd", "LIST"},
        {"mhd_missing_raw.mhd", "does not exist"},
        {"mhd_nan_origin.mhd", "not finite"},
        {"mhd_ndims4.mhd", "NDims = 4"},
        {"mhd_negative_spacing.mhd", "voxel spacing of axis 1 is -1"},
        {"mhd_singular_matrix.mhd", "degenerate"},
        {"nii_bad_dim.nii", "dim[1] = 0"},
        {"nii_empty.nii", ": is empty"},
        {"nii_huge_dims.nii", "memory limit"},
        {"nii_nan_pixdim.nii", "pixdim[2] = nan is not a positive voxel size"},
        {"nii_gz_vox_offset_past_end.nii.gz", "truncated: holds 0 bytes of voxel data after vox_offset 3000000000"},
        {"nii_tiny_spacing.nii", "voxel spacing along axis 2 is 7.458340731200207e-155 mm, below the 0.0001 mm"},
        {"nii_truncated.nii.gz", "truncated"},
        {"nii_wrong_magic.nii", "wrong magic 'n+2'"},
        {"nii_zero_spacing.nii", "pixdim[2] = 0"},
        {"nrrd_bad_type.nrrd", "unsupported type 'int64'"},
        {"nrrd_bzip2.nrrd", "unsupported encoding 'bzip2'"},
        {"nrrd_empty.nrrd", ": is empty"},
        {"nrrd_gzip_corrupt.nrrd", "corrupt"},
        {"nrrd_gzip_trailer_cut.nrrd", "compressed data is truncated: it ends before its checksum"},
        {"nrrd_huge_dims.nrrd", "memory limit"},
        {"nrrd_huge_origin.nrrd", "its voxels lie up to 1e+308 mm from the origin, beyond the 1e6 mm (1 km) limit"},
        {"nrrd_label_too_big.nrrd", "label 4000000000 does not fit a 32-bit signed label"},
        {"nrrd_missing_datafile.nhdr", "does not exist"},
        {"nrrd_missing_endian.nrrd", "no 'endian' field"},
        {"nrrd_nan_origin.nrrd", "not finite"},
        {"nrrd_negative_spacing.nrrd", "'spacings' of axis 1 is -2"},
        {"nrrd_sizes_count.nrrd", "'sizes' has 2 values, expected 3 for dimension 3"},
        {"nrrd_truncated.nrrd", "truncated"},
        {"nrrd_vector_axis.nrrd", "not spatial"},
        {"nrrd_wrong_magic.nrrd", "not a NRRD file"},
        {"nrrd_zero_direction.nrrd", "zero length"},
        {"seg_bad_color.seg.nrrd", "Segment0_Color '230 128 100' is not three numbers from 0 to 1"},
        {"seg_layers_last.seg.nrrd", "axis 3 (2 samples) is not spatial"},
        {"seg_missing_layer.seg.nrrd", "segment 'spot' is in layer 3, but the file has 1 layer(s)"},
        {"seg_no_segments.seg.nrrd", "names no segment (no Segment0_ID key)"},
    };
    const fs::path bad = fs::path(VOX_TEST_DATA_DIR) / "bad";
    std::size_t seen = 0;
    for (const auto& entry : fs::directory_iterator(bad)) {
        const std::string name = entry.path().filename().string();
        const std::string prefix = name.substr(0, name.find('_') + 1);
        if (prefix != "dicom_" && prefix != "mha_" && prefix != "mhd_" && prefix != "nrrd_" && prefix != "nii_" && prefix != "seg_")
            continue;
        SCOPED_TRACE(name);
        ++seen;
        const auto it = expected.find(name);
        ASSERT_NE(it, expected.end()) << "add " << name << " to this table and to tests/data/bad/README.md";
        try {
            (void)import_object(entry.path().string(), ImportOptions{});
            ADD_FAILURE() << "imported without an error";
        } catch (const InputError& e) {
            const std::string message = e.what();
            EXPECT_EQ(message.rfind(entry.path().string() + ": ", 0), 0u) << message;
            EXPECT_NE(message.find(it->second), std::string::npos) << message;
            EXPECT_EQ(message.find('\n'), std::string::npos) << message;
        }
    }
    EXPECT_EQ(seen, expected.size()) << "a file listed here is missing from " << bad;
}

} // namespace
} // namespace vox::io
