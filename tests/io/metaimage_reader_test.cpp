// MetaImage reader: conventions checked against ITK's MetaIO (TransformMatrix values [3a..3a+2] are
// index axis a's direction, Offset is voxel (0,0,0)'s centre), byte orders, data placement
// (LOCAL, detached, HeaderSize), compression, and a clear refusal for each kind of bad header.

#include "core/error.hpp"
#include "core/memory_limit.hpp"
#include "io/test_volume_writers.hpp"
#include "io/volume_reader.hpp"
#include "test_support.hpp"

#include <Eigen/Geometry>
#include <gtest/gtest.h>

#include <cstring>
#include <filesystem>
#include <fstream>

namespace vox::io {
namespace {

namespace fs = std::filesystem;

using test::be16;
using test::le16;
using test::world;

class MetaImageReader : public ::testing::Test {
  protected:
    [[nodiscard]] std::string path(const std::string& name) const { return m_dir.path(name); }

    /// Writes `header` then `data` bytes to `name` in the test folder; returns the full path.
    std::string write(const std::string& name, const std::string& header, const std::string& data = {}) const
    {
        return m_dir.write(name, header + data);
    }

    test::ScratchDir m_dir;
};

void expect_refused(const std::string& file, const std::string& problem)
{
    test::expect_refused([&] { (void)read_metaimage(file); }, file, problem);
}

const std::string k_head = "ObjectType = Image\nNDims = 3\nBinaryData = True\nBinaryDataByteOrderMSB = False\n";

TEST_F(MetaImageReader, TransformMatrixRowsAreIndexAxisDirectionsAsInItk)
{
    // ITK (MetaImageIO::ReadImageInformation) calls SetDirection(a, values[3a .. 3a+2]): index axis
    // 0 points along +y, axis 1 along -x, axis 2 along +z. A reader taking the values as rows
    // would put voxel (1,0,0) at (10, 18, 30) instead.
    const std::string file = write("rot.mha",
                                   k_head + "TransformMatrix = 0 1 0 -1 0 0 0 0 1\n"
                                            "Offset = 10 20 30\nElementSpacing = 2 3 4\nDimSize = 2 2 2\n"
                                            "ElementType = MET_UCHAR\nElementDataFile = LOCAL\n",
                                   std::string(8, '\0'));
    const Volume v = read_metaimage(file);
    EXPECT_TRUE(world(v, 0, 0, 0).isApprox(Eigen::Vector3d(10, 20, 30)));
    EXPECT_TRUE(world(v, 1, 0, 0).isApprox(Eigen::Vector3d(10, 22, 30))) << world(v, 1, 0, 0).transpose();
    EXPECT_TRUE(world(v, 0, 1, 0).isApprox(Eigen::Vector3d(7, 20, 30))) << world(v, 0, 1, 0).transpose();
    EXPECT_TRUE(world(v, 0, 0, 1).isApprox(Eigen::Vector3d(10, 20, 34))) << world(v, 0, 0, 1).transpose();
    EXPECT_TRUE(v.spacing().isApprox(Eigen::Vector3d(2, 3, 4)));
}

TEST_F(MetaImageReader, RotationAndOrientationAreAliasesOfTransformMatrix)
{
    const std::string body = "Offset = 1 2 3\nDimSize = 1 1 1\nElementType = MET_UCHAR\nElementDataFile = LOCAL\n";
    const Volume a = read_metaimage(write("a.mha", k_head + "TransformMatrix = 0 0 1 1 0 0 0 1 0\n" + body, "x"));
    const Volume b = read_metaimage(write("b.mha", k_head + "Rotation = 0 0 1 1 0 0 0 1 0\n" + body, "x"));
    const Volume c = read_metaimage(write("c.mha", k_head + "Orientation = 0 0 1 1 0 0 0 1 0\n" + body, "x"));
    EXPECT_EQ(a.index_to_world, b.index_to_world);
    EXPECT_EQ(a.index_to_world, c.index_to_world);
    EXPECT_EQ(a.index_to_world.col(0).head<3>(), Eigen::Vector3d(0, 0, 1));
}

TEST_F(MetaImageReader, OriginAndPositionAreAliasesOfOffset)
{
    const std::string body = "DimSize = 1 1 1\nElementType = MET_UCHAR\nElementDataFile = LOCAL\n";
    for (const char* key : {"Offset", "Origin", "Position"}) {
        const Volume v = read_metaimage(write("o.mha", k_head + key + " = -1.5 2.25 7\n" + body, "x"));
        EXPECT_EQ(world(v, 0, 0, 0), Eigen::Vector3d(-1.5, 2.25, 7)) << key;
    }
    // Aliases that agree are fine; aliases that disagree leave the origin ambiguous.
    EXPECT_NO_THROW((void)read_metaimage(write("same.mha", k_head + "Offset = 1 2 3\nOrigin = 1 2 3\n" + body, "x")));
    expect_refused(write("differ.mha", k_head + "Offset = 1 2 3\nOrigin = 1 2 4\n" + body, "x"), "different values");
}

TEST_F(MetaImageReader, ElementSizeStandsInOnlyForMissingElementSpacing)
{
    const std::string body = "DimSize = 1 1 1\nElementType = MET_UCHAR\nElementDataFile = LOCAL\n";
    const Volume size_only = read_metaimage(write("a.mha", k_head + "ElementSize = 2 3 4\n" + body, "x"));
    EXPECT_EQ(size_only.spacing(), Eigen::Vector3d(2, 3, 4));
    const Volume both =
        read_metaimage(write("b.mha", k_head + "ElementSize = 2 3 4\nElementSpacing = 0.5 0.5 1\n" + body, "x"));
    EXPECT_EQ(both.spacing(), Eigen::Vector3d(0.5, 0.5, 1));
    const Volume neither = read_metaimage(write("c.mha", k_head + body, "x"));
    EXPECT_EQ(neither.index_to_world, Eigen::Matrix4d::Identity());
}

TEST_F(MetaImageReader, AnatomicalOrientationDoesNotChangeTheTransform)
{
    // ITK ignores AnatomicalOrientation when building the image geometry; so do we.
    const std::string body = "Offset = 1 2 3\nDimSize = 1 1 1\nElementType = MET_UCHAR\nElementDataFile = LOCAL\n";
    const Volume plain = read_metaimage(write("a.mha", k_head + body, "x"));
    const Volume ras = read_metaimage(write("b.mha", k_head + "AnatomicalOrientation = RAI\n" + body, "x"));
    EXPECT_EQ(plain.index_to_world, ras.index_to_world);
}

TEST_F(MetaImageReader, ReadsBigEndianData)
{
    const std::string body = "DimSize = 3 1 1\nElementType = MET_SHORT\nElementDataFile = LOCAL\n";
    const std::string head = "ObjectType = Image\nNDims = 3\n";
    for (const char* key : {"BinaryDataByteOrderMSB", "ElementByteOrderMSB"}) {
        const Volume v = read_metaimage(write("be.mha", head + key + " = True\n" + body, be16({-2, 300, 7})));
        ASSERT_EQ(v.voxel_count(), 3);
        EXPECT_EQ(v.stored(0), -2) << key;
        EXPECT_EQ(v.stored(1), 300) << key;
        EXPECT_EQ(v.stored(2), 7) << key;
    }
    expect_refused(write("clash.mha", head + "BinaryDataByteOrderMSB = True\nElementByteOrderMSB = False\n" + body,
                         be16({1, 2, 3})),
                   "disagree");
}

TEST_F(MetaImageReader, DetachedDataIsRelativeToTheHeaderFolder)
{
    fs::create_directories(m_dir.root() / "sub");
    write("sub/voxels.raw", "", le16({5, -6}));
    const std::string file =
        write("a.mhd", k_head + "DimSize = 2 1 1\nElementType = MET_SHORT\nElementDataFile = sub/voxels.raw\n");
    const auto cwd = fs::current_path();
    fs::current_path(fs::temp_directory_path());
    const Volume v = read_metaimage(file);
    fs::current_path(cwd);
    EXPECT_EQ(v.stored(0), 5);
    EXPECT_EQ(v.stored(1), -6);
    EXPECT_EQ(v.source, file);
    const Volume absolute = read_metaimage(write("abs.mhd", k_head +
                                                                "DimSize = 2 1 1\nElementType = MET_SHORT\n"
                                                                "ElementDataFile = " +
                                                                path("sub/voxels.raw") + "\n"));
    EXPECT_EQ(absolute.data, v.data);
}

TEST_F(MetaImageReader, HeaderSizeSkipsBytesAndMinusOneReadsTheEnd)
{
    write("skip.raw", "", "JUNK!" + le16({11, 12}));
    const Volume skipped = read_metaimage(write(
        "a.mhd", k_head + "HeaderSize = 5\nDimSize = 2 1 1\nElementType = MET_SHORT\nElementDataFile = skip.raw\n"));
    EXPECT_EQ(skipped.stored(0), 11);
    EXPECT_EQ(skipped.stored(1), 12);

    write("tail.raw", "", "a DICOM-like preamble of unknown size" + le16({21, 22}));
    const Volume tail = read_metaimage(write(
        "b.mhd", k_head + "HeaderSize = -1\nDimSize = 2 1 1\nElementType = MET_SHORT\nElementDataFile = tail.raw\n"));
    EXPECT_EQ(tail.stored(0), 21);
    EXPECT_EQ(tail.stored(1), 22);
}

TEST_F(MetaImageReader, TwoDimensionalImageIsOneSlice)
{
    const Volume v = read_metaimage(write("slice.mha",
                                          "ObjectType = Image\nNDims = 2\nTransformMatrix = 0 1 -1 0\nOffset = 4 5\n"
                                          "ElementSpacing = 0.5 2\nDimSize = 3 2\nElementType = MET_UCHAR\n"
                                          "ElementDataFile = LOCAL\n",
                                          std::string(6, '\1')));
    EXPECT_EQ(v.dims, (std::array<std::int64_t, 3>{3, 2, 1}));
    EXPECT_EQ(world(v, 1, 0, 0), Eigen::Vector3d(4, 5.5, 0));
    EXPECT_EQ(world(v, 0, 1, 0), Eigen::Vector3d(2, 5, 0));
    EXPECT_EQ(world(v, 0, 0, 1), Eigen::Vector3d(4, 5, 1));
}

TEST_F(MetaImageReader, RoundTripsEveryLayoutOfTheTestWriter)
{
    Volume v;
    v.dims = {4, 3, 2};
    v.type = ScalarType::f32;
    const Eigen::Matrix3d rotation = Eigen::AngleAxisd(0.3, Eigen::Vector3d(1, 2, 3).normalized()).toRotationMatrix();
    v.index_to_world = make_index_to_world(Eigen::Vector3d(0.3, 0.7, 1.1), rotation, Eigen::Vector3d(-5.5, 3.25, 100));
    v.data.resize(24 * sizeof(float));
    for (int n = 0; n < 24; ++n) {
        const float value = static_cast<float>(n) * -1.5f + 0.125f;
        std::memcpy(v.data.data() + n * sizeof(float), &value, sizeof(float));
    }
    for (const auto& [name, compressed] : std::vector<std::pair<std::string, bool>>{
             {"plain.mha", false}, {"zipped.mha", true}, {"plain.mhd", false}, {"zipped.mhd", true}}) {
        test::write_metaimage(v, path(name), compressed);
        const Volume r = read_metaimage(path(name));
        EXPECT_EQ(r.dims, v.dims) << name;
        EXPECT_EQ(r.type, v.type) << name;
        EXPECT_EQ(r.data, v.data) << name;
        EXPECT_LE((r.index_to_world - v.index_to_world).cwiseAbs().maxCoeff(), 1e-12) << name;
    }
    // CompressedDataSize is optional: without it the compressed bytes run to the end of the file.
    std::ifstream in(path("zipped.mha"), std::ios::binary);
    std::string text((std::istreambuf_iterator<char>(in)), {});
    const auto at = text.find("CompressedDataSize");
    text.erase(at, text.find('\n', at) + 1 - at);
    EXPECT_EQ(read_metaimage(write("nosize.mha", text)).data, v.data);
}

TEST_F(MetaImageReader, RefusesUnsupportedContent)
{
    const std::string dims = "DimSize = 2 1 1\n";
    expect_refused(
        write("t.mha", k_head + dims + "ElementType = MET_LONG_LONG\nElementDataFile = LOCAL\n", "0123456789abcdef"),
        "unsupported ElementType 'MET_LONG_LONG'");
    expect_refused(
        write("c.mha",
              k_head + dims + "ElementNumberOfChannels = 3\nElementType = MET_UCHAR\nElementDataFile = LOCAL\n",
              "123456"),
        "single-channel");
    expect_refused(write("a.mha", "ObjectType = Image\nNDims = 3\nBinaryData = False\n" + dims +
                                      "ElementType = MET_UCHAR\nElementDataFile = LOCAL\n1 2\n"),
                   "BinaryData = False");
    expect_refused(write("l.mhd", k_head + dims + "ElementType = MET_UCHAR\nElementDataFile = LIST\ns0.raw\n"), "LIST");
    expect_refused(write("p.mhd", k_head + dims + "ElementType = MET_UCHAR\nElementDataFile = slice%03d.raw 1 2 1\n"),
                   "numbered pattern");
    expect_refused(write("n.mhd",
                         "ObjectType = Image\nNDims = 4\nDimSize = 2 1 1 1\nElementType = MET_UCHAR\n"
                         "ElementDataFile = LOCAL\n",
                         "12"),
                   "NDims = 4");
    expect_refused(
        write("o.mha", "ObjectType = Scene\nNDims = 3\n" + dims + "ElementType = MET_UCHAR\nElementDataFile = LOCAL\n",
              "12"),
        "ObjectType");
}

TEST_F(MetaImageReader, RefusesBadGeometry)
{
    const std::string tail = "ElementType = MET_UCHAR\nElementDataFile = LOCAL\n";
    expect_refused(write("d.mhd", k_head + "DimSize = 2 1\n" + tail, "12"),
                   "'DimSize' has 2 values, expected 3 for NDims 3");
    expect_refused(write("z.mhd", k_head + "DimSize = 2 0 1\n" + tail, "12"), "'DimSize' of axis 1 is 0");
    expect_refused(write("s.mhd", k_head + "ElementSpacing = 1 -1 1\nDimSize = 2 1 1\n" + tail, "12"),
                   "voxel spacing of axis 1");
    expect_refused(write("s0.mhd", k_head + "ElementSpacing = 1 1 0\nDimSize = 2 1 1\n" + tail, "12"),
                   "voxel spacing of axis 2");
    expect_refused(write("nan.mhd", k_head + "Offset = 0 nan 0\nDimSize = 2 1 1\n" + tail, "12"),
                   "'nan' is not finite");
    expect_refused(write("inf.mhd", k_head + "ElementSpacing = 1 inf 1\nDimSize = 2 1 1\n" + tail, "12"),
                   "is not finite");
    expect_refused(write("txt.mhd", k_head + "Offset = 0 zero 0\nDimSize = 2 1 1\n" + tail, "12"), "is not a number");
    expect_refused(write("m.mhd", k_head + "TransformMatrix = 1 0 0\nDimSize = 2 1 1\n" + tail, "12"),
                   "'TransformMatrix' has 3 values, expected 9");
    expect_refused(write("sing.mhd", k_head + "TransformMatrix = 1 0 0 1 0 0 0 0 1\nDimSize = 2 1 1\n" + tail, "12"),
                   "degenerate");
}

TEST_F(MetaImageReader, RefusesMissingOrMismatchedData)
{
    const std::string head = k_head + "DimSize = 4 1 1\nElementType = MET_SHORT\n";
    expect_refused(path("absent.mha"), "no such file");
    expect_refused(write("nodata.mhd", head + "ElementDataFile = nowhere.raw\n"), "nowhere.raw");
    expect_refused(write("short.mha", head + "ElementDataFile = LOCAL\n", le16({1, 2, 3})), "truncated");
    expect_refused(write("long.mha", head + "ElementDataFile = LOCAL\n", le16({1, 2, 3, 4, 5})),
                   "the header does not describe this data");
    expect_refused(write("zip.mha",
                         k_head + "CompressedData = True\nDimSize = 4 1 1\nElementType = MET_SHORT\n"
                                  "ElementDataFile = LOCAL\n",
                         "not zlib"),
                   "corrupt compressed data");
    expect_refused(write("nokey.mha", k_head + "DimSize = 4 1 1\nElementType = MET_SHORT\n"), "no 'ElementDataFile'");
    expect_refused(write("binary.mha", std::string("\x89PNG\r\n\x1a\n", 8)), "not a MetaImage header");
    expect_refused(write("dup.mha", k_head + "DimSize = 4 1 1\nDimSize = 4 1 1\n"), "appears twice");
}

TEST_F(MetaImageReader, BinaryFilesAreNotEchoed)
{
    // A scan of another format named .mha: say it holds binary data instead of quoting its bytes.
    const std::string gz = write("scan.mha", test::gzip("#INRIMAGE-4#{\nXDIM=2\n"));
    const std::string message = test::error_of([&] { (void)read_metaimage(gz); });
    EXPECT_EQ(message, gz + ": not a MetaImage header: line 1 holds binary data, not 'Key = value' text");
    // Text that is not a header is still quoted, so the user sees what it is.
    expect_refused(write("text.mha", "ply\nformat ascii 1.0\n"), "line 1 is not 'Key = value' ('ply')");
    expect_refused(write("empty.mha", ""), ": is empty");
    fs::create_directories(path("folder.mha"));
    expect_refused(path("folder.mha"), ": is a folder, not a file");
    fs::create_directories(path("voxels.raw"));
    expect_refused(
        write("detached.mhd", k_head + "DimSize = 1 1 1\nElementType = MET_UCHAR\nElementDataFile = voxels.raw\n"),
        "(ElementDataFile) is a folder, not a file");
}

TEST_F(MetaImageReader, RefusesHugeDimensionsBeforeAllocating)
{
    // 4096^3 floats need 256 GiB: the header alone must be refused, with no data present at all.
    expect_refused(
        write("huge.mha", k_head + "DimSize = 4096 4096 4096\nElementType = MET_FLOAT\nElementDataFile = LOCAL\n"),
        "memory limit");
    expect_refused(write("overflow.mha", k_head +
                                             "DimSize = 4294967296 4294967296 4294967296\nElementType = MET_UCHAR\n"
                                             "ElementDataFile = LOCAL\n"),
                   "overflow");
    const std::uint64_t saved = memory_limit_bytes();
    set_memory_limit_bytes(1024);
    expect_refused(write("limit.mha", k_head + "DimSize = 32 32 1\nElementType = MET_SHORT\nElementDataFile = LOCAL\n",
                         std::string(2048, '\0')),
                   "memory limit");
    set_memory_limit_bytes(saved);
}

} // namespace
} // namespace vox::io
