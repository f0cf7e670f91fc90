#include "io/selection.hpp"
#include "io/volume_reader.hpp"

#include "core/error.hpp"

#include <gtest/gtest.h>

#include <fstream>

namespace fs = std::filesystem;
using namespace vox::io;

namespace {
const std::string k_liver = VOX_SOURCE_DIR "/data/liver.inr.gz";

/// Writes a tiny INR by hand, with the header padded to `header_size` bytes.
std::string write_small_inr(const std::string& name, const std::string& fields, const std::string& data,
                            std::size_t header_size)
{
    std::string h = "#INRIMAGE-4#{\n" + fields;
    h += std::string(header_size - h.size() - 4, '\n') + "##}\n";
    const std::string path = (fs::path(::testing::TempDir()) / name).string();
    std::ofstream(path, std::ios::binary) << h << data;
    return path;
}
} // namespace

TEST(InrReader, ReadsTheLiverHeaderAndVoxels)
{
    const Volume v = read_volume(k_liver);
    EXPECT_EQ(v.dims, (std::array<std::int64_t, 3>{438, 353, 165}));
    EXPECT_EQ(v.type, ScalarType::u8);
    EXPECT_NEAR(v.spacing().x(), 0.617188, 1e-12);
    EXPECT_NEAR(v.spacing().y(), 0.617188, 1e-12);
    EXPECT_NEAR(v.spacing().z(), 1.33333, 1e-12);
    EXPECT_TRUE((v.index_to_world.topRightCorner<3, 1>().isZero()));
}

TEST(InrReader, LiverLabelCountsMatchTheDataSet)
{
    // The counts published with the sample data (../shared/data/README.md).
    const Volume v = read_volume(k_liver);
    Selection s;
    s.labels = {255};
    EXPECT_EQ(select_voxels(v, s).active_voxel_count(), 3160496u);
    const auto all = select_voxels(v, Selection{}).label_histogram();
    EXPECT_EQ(all.at(255), 3160496u);
    EXPECT_EQ(all.at(127), 314086u);
    EXPECT_EQ(all.at(85), 17702u);
    EXPECT_EQ(all.at(84), 2u);
    EXPECT_EQ(all.size(), 4u);
}

TEST(InrReader, HeaderOfOtherSizeBigEndianAndOrigin)
{
    // 240-byte header (CGAL's small-scalar.inr has one), big-endian 16-bit signed, with origin.
    const std::string fields = "XDIM=2\nYDIM=1\nZDIM=1\nVDIM=1\nTYPE=signed fixed\nPIXSIZE=16 bits\nCPU=sun\n"
                               "VX=0.5\nVY=2\nVZ=3\nXO=10\nYO=-4\nZO=1.5\n";
    const std::string data{"\x01\x02\xff\xfe", 4}; // 0x0102 = 258, 0xfffe = -2
    const Volume v = read_volume(write_small_inr("be.inr", fields, data, 240));
    EXPECT_EQ(v.type, ScalarType::i16);
    EXPECT_EQ(v.stored(0), 258.0);
    EXPECT_EQ(v.stored(1), -2.0);
    EXPECT_TRUE((v.index_to_world.topRightCorner<3, 1>().isApprox(Eigen::Vector3d(10, -4, 1.5))));
    EXPECT_TRUE(v.spacing().isApprox(Eigen::Vector3d(0.5, 2, 3)));
}

TEST(InrReader, FloatVoxels)
{
    const std::string fields = "XDIM=1\nYDIM=1\nZDIM=2\nTYPE=float\nPIXSIZE=64 bits\nCPU=decm\nVX=1\nVY=1\nVZ=1\n";
    const double values[2] = {-1024.5, 3071.25};
    const Volume v =
        read_volume(write_small_inr("f64.inr", fields, std::string(reinterpret_cast<const char*>(values), 16), 256));
    EXPECT_EQ(v.type, ScalarType::f64);
    EXPECT_EQ(v.stored(0), -1024.5);
    EXPECT_EQ(v.stored(1), 3071.25);
}

TEST(InrReader, MalformedFilesNameTheFile)
{
    for (const char* name : {"inr_truncated.inr", "inr_wrong_magic.inr", "inr_no_header_end.inr", "inr_huge_dims.inr",
                             "inr_negative_spacing.inr", "inr_zero_spacing.inr", "inr_bad_type.inr",
                             "inr_nan_spacing.inr", "inr_empty.inr", "inr_truncated_gzip.inr.gz",
                             "inr_dims_overflow.inr"}) { // YDIM beyond 64 bits overflowed the voxel count (fuzzing)
        const std::string path = std::string(VOX_TEST_DATA_DIR) + "/bad/" + name;
        try {
            (void)read_volume(path);
            ADD_FAILURE() << name << " was accepted";
        } catch (const vox::InputError& e) {
            EXPECT_EQ(std::string(e.what()).rfind(path + ": ", 0), 0u) << e.what();
        }
    }
}
