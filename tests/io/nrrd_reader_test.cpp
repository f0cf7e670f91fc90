// NRRD reader: the space conventions (RAS and LAS converted to LPS), every type alias of teem's
// format definition, attached and detached data with line/byte skips, raw/gzip/ascii encodings,
// byte order, non-spatial axes, and a clear refusal for each kind of bad header.

#include "core/error.hpp"
#include "core/memory_limit.hpp"
#include "io/test_volume_writers.hpp"
#include "io/volume_reader.hpp"
#include "test_support.hpp"

#include <Eigen/Geometry>
#include <gtest/gtest.h>

#include <cstring>
#include <filesystem>

namespace vox::io {
namespace {

using test::be16;
using test::gzip;
using test::le16;
using test::world;

class NrrdReader : public ::testing::Test {
  protected:
    [[nodiscard]] std::string path(const std::string& name) const { return m_dir.path(name); }
    std::string write(const std::string& name, const std::string& content) const { return m_dir.write(name, content); }

    test::ScratchDir m_dir;
};

void expect_refused(const std::string& file, const std::string& problem)
{
    test::expect_refused([&] { (void)read_nrrd(file); }, file, problem);
}

/// An attached-data NRRD: magic, `fields` (one per line), blank line, data.
std::string nrrd(const std::string& fields, const std::string& data = {})
{
    return "NRRD0004\n" + fields + "\n" + data;
}

const std::string k_short3 = "type: short\ndimension: 3\nsizes: 3 1 1\nendian: little\n";

TEST_F(NrrdReader, RasSpaceIsConvertedToLpsByNegatingXAndY)
{
    const std::string geometry = "dimension: 3\nsizes: 1 1 1\ntype: uchar\nencoding: raw\n"
                                 "space directions: (0.5,0.25,0) (0,0.75,0.5) (1,0,1.25)\n"
                                 "space origin: (10,-20,30)\n";
    const Volume ras = read_nrrd(write("ras.nrrd", nrrd("space: right-anterior-superior\n" + geometry, "x")));
    Eigen::Matrix4d expected;
    expected << -0.5, 0, -1, -10, //
        -0.25, -0.75, 0, 20,      //
        0, 0.5, 1.25, 30,         //
        0, 0, 0, 1;
    EXPECT_EQ(ras.index_to_world, expected);
    // Voxel (1,0,0) is 0.5 mm towards the patient's right in RAS x, i.e. -0.5 in LPS x.
    EXPECT_EQ(world(ras, 1, 0, 0), Eigen::Vector3d(-10.5, 19.75, 30));
    const Volume short_name = read_nrrd(write("ras2.nrrd", nrrd("space: RAS\n" + geometry, "x")));
    EXPECT_EQ(short_name.index_to_world, expected);
}

TEST_F(NrrdReader, LasSpaceNegatesYOnly)
{
    const std::string geometry = "dimension: 3\nsizes: 1 1 1\ntype: uchar\nencoding: raw\n"
                                 "space directions: (1,2,3) (0,1,0) (0,0,1)\nspace origin: (4,5,6)\n";
    const Volume las = read_nrrd(write("las.nrrd", nrrd("space: left-anterior-superior\n" + geometry, "x")));
    EXPECT_EQ(las.index_to_world.col(0).head<3>(), Eigen::Vector3d(1, -2, 3));
    EXPECT_EQ(las.index_to_world.col(1).head<3>(), Eigen::Vector3d(0, -1, 0));
    EXPECT_EQ(world(las, 0, 0, 0), Eigen::Vector3d(4, -5, 6));
    for (const char* same :
         {"left-posterior-superior", "left posterior superior", "LPS", "scanner-xyz", "3D-right-handed"}) {
        const Volume v = read_nrrd(write("lps.nrrd", nrrd(std::string("space: ") + same + "\n" + geometry, "x")));
        EXPECT_EQ(v.index_to_world.col(0).head<3>(), Eigen::Vector3d(1, 2, 3)) << same;
        EXPECT_EQ(world(v, 0, 0, 0), Eigen::Vector3d(4, 5, 6)) << same;
    }
}

TEST_F(NrrdReader, SpacingsWithoutSpaceGiveAnAxisAlignedGrid)
{
    const Volume v =
        read_nrrd(write("s.nrrd", nrrd(k_short3 + "spacings: 0.5 0.75 1.25\nencoding: raw\n", le16({1, 2, 3}))));
    EXPECT_EQ(v.index_to_world, Eigen::Vector4d(0.5, 0.75, 1.25, 1).asDiagonal().toDenseMatrix());
    const Volume none = read_nrrd(write("n.nrrd", nrrd(k_short3 + "encoding: raw\n", le16({1, 2, 3}))));
    EXPECT_EQ(none.index_to_world, Eigen::Matrix4d::Identity());
}

TEST_F(NrrdReader, AcceptsEveryTypeAliasOfTheFormat)
{
    const std::vector<std::pair<const char*, ScalarType>> aliases = {{"signed char", ScalarType::i8},
                                                                     {"int8", ScalarType::i8},
                                                                     {"int8_t", ScalarType::i8},
                                                                     {"uchar", ScalarType::u8},
                                                                     {"unsigned char", ScalarType::u8},
                                                                     {"uint8", ScalarType::u8},
                                                                     {"uint8_t", ScalarType::u8},
                                                                     {"short", ScalarType::i16},
                                                                     {"short int", ScalarType::i16},
                                                                     {"signed short", ScalarType::i16},
                                                                     {"signed short int", ScalarType::i16},
                                                                     {"int16", ScalarType::i16},
                                                                     {"int16_t", ScalarType::i16},
                                                                     {"ushort", ScalarType::u16},
                                                                     {"unsigned short", ScalarType::u16},
                                                                     {"unsigned short int", ScalarType::u16},
                                                                     {"uint16", ScalarType::u16},
                                                                     {"uint16_t", ScalarType::u16},
                                                                     {"int", ScalarType::i32},
                                                                     {"signed int", ScalarType::i32},
                                                                     {"int32", ScalarType::i32},
                                                                     {"int32_t", ScalarType::i32},
                                                                     {"uint", ScalarType::u32},
                                                                     {"unsigned int", ScalarType::u32},
                                                                     {"uint32", ScalarType::u32},
                                                                     {"uint32_t", ScalarType::u32},
                                                                     {"float", ScalarType::f32},
                                                                     {"double", ScalarType::f64},
                                                                     {"Unsigned  Short", ScalarType::u16}};
    for (const auto& [alias, type] : aliases) {
        const std::string file =
            write("t.nrrd",
                  nrrd(std::string("type: ") + alias + "\ndimension: 3\nsizes: 1 1 1\nendian: little\nencoding: raw\n",
                       std::string(scalar_size(type), '\0')));
        EXPECT_EQ(read_nrrd(file).type, type) << alias;
    }
    for (const char* unsupported : {"int64", "unsigned long long", "block", "char", "half"})
        expect_refused(write("bad.nrrd", nrrd(std::string("type: ") + unsupported +
                                                  "\ndimension: 3\nsizes: 1 1 1\nendian: little\nencoding: raw\n",
                                              "12345678")),
                       std::string("unsupported type '") + unsupported + "'");
}

TEST_F(NrrdReader, DetachedDataWithLineAndByteSkip)
{
    write("voxels.dat", "a text preamble\nof two lines\nXYZ" + le16({-7, 8, 9}));
    for (const char* key : {"data file", "datafile"}) {
        const std::string header =
            "NRRD0004\n" + k_short3 + "encoding: raw\n" + key + ": voxels.dat\nline skip: 2\nbyte skip: 3\n";
        const Volume v = read_nrrd(write("d.nhdr", header));
        EXPECT_EQ(v.stored(0), -7) << key;
        EXPECT_EQ(v.stored(2), 9) << key;
    }
    // An absolute data file path is used as is.
    const Volume absolute =
        read_nrrd(write("abs.nhdr", "NRRD0004\n" + k_short3 + "encoding: raw\ndata file: " + path("voxels.dat") +
                                        "\nline skip: 2\nbyte skip: 3\n"));
    EXPECT_EQ(absolute.stored(0), -7);
    // A detached header may also end with a blank line.
    const Volume blank = read_nrrd(write(
        "b.nhdr", "NRRD0004\n" + k_short3 + "encoding: raw\ndata file: voxels.dat\nline skip: 2\nbyte skip: 3\n\n"));
    EXPECT_EQ(blank.stored(1), 8);
}

TEST_F(NrrdReader, ByteSkipMinusOneReadsTheLastBytes)
{
    write("tail.raw", "header of some other format, any length" + le16({31, 32, 33}));
    const Volume v =
        read_nrrd(write("t.nhdr", "NRRD0005\n" + k_short3 + "encoding: raw\ndata file: tail.raw\nbyte skip: -1\n"));
    EXPECT_EQ(v.stored(0), 31);
    EXPECT_EQ(v.stored(2), 33);
}

TEST_F(NrrdReader, GzipByteSkipCountsDecompressedBytes)
{
    // teem's _nrrdEncodingGzip_read skips byte-skip bytes of the decompressed stream.
    const std::string zipped = gzip("SKIP" + le16({-1, 2, -3}));
    const Volume attached = read_nrrd(write("g.nrrd", nrrd(k_short3 + "encoding: gzip\nbyte skip: 4\n", zipped)));
    EXPECT_EQ(attached.stored(0), -1);
    EXPECT_EQ(attached.stored(2), -3);
    write("g.raw.gz", zipped);
    const Volume detached =
        read_nrrd(write("g.nhdr", "NRRD0004\n" + k_short3 + "encoding: gz\nbyte skip: 4\ndata file: g.raw.gz\n"));
    EXPECT_EQ(detached.data, attached.data);
}

TEST_F(NrrdReader, AsciiEncoding)
{
    const Volume s = read_nrrd(
        write("a.nrrd", nrrd("type: short\ndimension: 3\nsizes: 3 1 1\nencoding: ascii\n", "-5 17\n 32767\n")));
    EXPECT_EQ(s.stored(0), -5);
    EXPECT_EQ(s.stored(1), 17);
    EXPECT_EQ(s.stored(2), 32767);
    const Volume f =
        read_nrrd(write("f.nrrd", nrrd("type: double\ndimension: 3\nsizes: 2 1 1\nencoding: text\n", "0.1, -2.5e3")));
    EXPECT_EQ(f.stored(0), 0.1);
    EXPECT_EQ(f.stored(1), -2500.0);
    expect_refused(write("few.nrrd", nrrd("type: short\ndimension: 3\nsizes: 3 1 1\nencoding: ascii\n", "1 2")),
                   "truncated");
    expect_refused(write("many.nrrd", nrrd("type: short\ndimension: 3\nsizes: 3 1 1\nencoding: ascii\n", "1 2 3 4")),
                   "more than the 3 values");
    expect_refused(write("range.nrrd", nrrd("type: uchar\ndimension: 3\nsizes: 1 1 1\nencoding: ascii\n", "256")),
                   "does not fit");
    expect_refused(write("word.nrrd", nrrd("type: float\ndimension: 3\nsizes: 1 1 1\nencoding: ascii\n", "one")),
                   "is not a number");
}

TEST_F(NrrdReader, BigEndianRawAndGzip)
{
    const std::string big = "type: int16\ndimension: 3\nsizes: 3 1 1\nendian: big\n";
    const Volume raw = read_nrrd(write("r.nrrd", nrrd(big + "encoding: raw\n", be16({-300, 1, 256}))));
    EXPECT_EQ(raw.stored(0), -300);
    EXPECT_EQ(raw.stored(1), 1);
    EXPECT_EQ(raw.stored(2), 256);
    const Volume zipped = read_nrrd(write("g.nrrd", nrrd(big + "encoding: gzip\n", gzip(be16({-300, 1, 256})))));
    EXPECT_EQ(zipped.data, raw.data);
}

TEST_F(NrrdReader, IgnoresCommentsKeyValuePairsAndDescriptiveFields)
{
    const std::string header = "# a comment: with a colon\n"
                               "Type: short\nDIMENSION: 3\nsizes: 3 1 1\nendian: little\nencoding: raw\n"
                               "my key:=a value: with a colon\n"
                               "content: test\nlabels: \"x\" \"y\" \"z\"\ncenters: cell cell cell\n"
                               "thicknesses: nan nan nan\nmeasurement frame: (1,0,0) (0,1,0) (0,0,1)\n";
    const Volume v = read_nrrd(write("c.nrrd", nrrd(header, le16({4, 5, 6}))));
    EXPECT_EQ(v.stored(1), 5);
}

TEST_F(NrrdReader, DropsSingletonNonSpatialAxesAndReadsSlices)
{
    // A 4-D file whose first axis is a one-sample "scalar" axis is a plain 3-D volume.
    const Volume v = read_nrrd(write("four.nrrd", nrrd("type: uchar\ndimension: 4\nsizes: 1 3 2 1\n"
                                                       "space: left-posterior-superior\n"
                                                       "space directions: none (2,0,0) (0,3,0) (0,0,4)\n"
                                                       "kinds: scalar domain domain domain\nencoding: raw\n",
                                                       "abcdef")));
    EXPECT_EQ(v.dims, (std::array<std::int64_t, 3>{3, 2, 1}));
    EXPECT_EQ(v.spacing(), Eigen::Vector3d(2, 3, 4));

    const Volume slice = read_nrrd(write("two.nrrd", nrrd("type: uchar\ndimension: 2\nsizes: 2 3\nspace: LPS\n"
                                                          "space directions: (0,2,0) (-3,0,0)\nspace origin: (1,1,1)\n"
                                                          "encoding: raw\n",
                                                          "abcdef")));
    EXPECT_EQ(slice.dims, (std::array<std::int64_t, 3>{2, 3, 1}));
    EXPECT_EQ(world(slice, 1, 0, 0), Eigen::Vector3d(1, 3, 1));
    EXPECT_EQ(world(slice, 0, 1, 0), Eigen::Vector3d(-2, 1, 1));
    EXPECT_EQ(world(slice, 0, 0, 1), Eigen::Vector3d(1, 1, 2)); // unit normal (0,2,0) x (-3,0,0) / 6
}

TEST_F(NrrdReader, RoundTripsTheTestWriter)
{
    Volume v;
    v.dims = {4, 3, 2};
    v.type = ScalarType::i32;
    const Eigen::Matrix3d rotation =
        Eigen::AngleAxisd(1.1, Eigen::Vector3d(-1, 2, 0.5).normalized()).toRotationMatrix();
    v.index_to_world = make_index_to_world(Eigen::Vector3d(0.3, 0.7, 1.1), rotation, Eigen::Vector3d(-5.5, 3.25, 100));
    v.data.resize(24 * sizeof(std::int32_t));
    for (int n = 0; n < 24; ++n) {
        const std::int32_t value = (n - 12) * 100003;
        std::memcpy(v.data.data() + n * sizeof(value), &value, sizeof(value));
    }
    for (const auto& [name, encoding] : std::vector<std::pair<std::string, std::string>>{
             {"a.nrrd", "raw"}, {"b.nrrd", "gzip"}, {"c.nhdr", "raw"}, {"d.nhdr", "gzip"}}) {
        test::write_nrrd(v, path(name), encoding);
        const Volume r = read_nrrd(path(name));
        EXPECT_EQ(r.dims, v.dims) << name;
        EXPECT_EQ(r.type, v.type) << name;
        EXPECT_EQ(r.data, v.data) << name;
        EXPECT_LE((r.index_to_world - v.index_to_world).cwiseAbs().maxCoeff(), 1e-12) << name;
    }
}

TEST_F(NrrdReader, RefusesBadHeaders)
{
    const std::string raw = "encoding: raw\n";
    expect_refused(write("magic.nrrd", "NRRD0009\n" + k_short3 + raw + "\n"),
                   "expected the magic NRRD0001 to NRRD0005");
    expect_refused(write("png.nrrd", std::string("\x89PNG\r\n\x1a\n", 8)), "not a NRRD file");
    expect_refused(write("endian.nrrd", nrrd("type: short\ndimension: 3\nsizes: 3 1 1\n" + raw, le16({1, 2, 3}))),
                   "no 'endian' field");
    expect_refused(write("enc.nrrd", nrrd(k_short3 + "encoding: bzip2\n", "BZh9")), "unsupported encoding 'bzip2'");
    expect_refused(write("hex.nrrd", nrrd(k_short3 + "encoding: hex\n", "000100020003")), "unsupported encoding 'hex'");
    expect_refused(write("field.nrrd", nrrd(k_short3 + raw + "spacing: 1 1 1\n", le16({1, 2, 3}))),
                   "unknown header field 'spacing'");
    expect_refused(write("twice.nrrd", nrrd(k_short3 + raw + "encoding: raw\n", le16({1, 2, 3}))), "appears twice");
    expect_refused(
        write("sizes.nrrd", nrrd("type: short\ndimension: 3\nsizes: 3 1\nendian: little\n" + raw, le16({1, 2, 3}))),
        "'sizes' has 2 values, expected 3 for dimension 3");
    expect_refused(write("nodim.nrrd", nrrd("type: short\nsizes: 3 1 1\nendian: little\n" + raw, le16({1, 2, 3}))),
                   "no 'dimension' field");
    expect_refused(
        write("dirs.nrrd", nrrd(k_short3 + raw + "space: LPS\nspace directions: (1,0,0) (0,1,0)\n", le16({1, 2, 3}))),
        "'space directions' has 2 values, expected 3");
    expect_refused(write("vec2.nrrd", nrrd(k_short3 + raw + "space: LPS\nspace directions: (1,0) (0,1,0) (0,0,1)\n",
                                           le16({1, 2, 3}))),
                   "has 2 components");
    expect_refused(write("zero.nrrd", nrrd(k_short3 + raw + "space: LPS\nspace directions: (0,0,0) (0,1,0) (0,0,1)\n",
                                           le16({1, 2, 3}))),
                   "zero length");
    expect_refused(write("nan.nrrd", nrrd(k_short3 + raw +
                                              "space: LPS\nspace directions: (1,0,0) (0,1,0) (0,0,1)\n"
                                              "space origin: (0,0,inf)\n",
                                          le16({1, 2, 3}))),
                   "is not finite");
    expect_refused(write("neg.nrrd", nrrd(k_short3 + raw + "spacings: 1 -1 1\n", le16({1, 2, 3}))),
                   "'spacings' of axis 1 is -1");
    expect_refused(write("both.nrrd", nrrd(k_short3 + raw +
                                               "space: LPS\nspacings: 1 1 1\n"
                                               "space directions: (1,0,0) (0,1,0) (0,0,1)\n",
                                           le16({1, 2, 3}))),
                   "'spacings' cannot be given with a space");
    expect_refused(write("time.nrrd", nrrd(k_short3 + raw + "space: right-anterior-superior-time\n", le16({1, 2, 3}))),
                   "unsupported space");
    expect_refused(write("cm.nrrd", nrrd(k_short3 + raw +
                                             "space: LPS\nspace directions: (1,0,0) (0,1,0) (0,0,1)\n"
                                             "space units: \"cm\" \"cm\" \"cm\"\n",
                                         le16({1, 2, 3}))),
                   "space units \"cm\"");
    expect_refused(
        write("rgb.nrrd",
              nrrd("type: uchar\ndimension: 4\nsizes: 3 1 1 1\nkinds: RGB-color domain domain domain\n" + raw, "rgb")),
        "axis 0 (3 samples) is not spatial");
    expect_refused(write("fourd.nrrd", nrrd("type: uchar\ndimension: 4\nsizes: 1 1 1 2\n" + raw, "ab")),
                   "has 4 spatial axes");
}

TEST_F(NrrdReader, BinaryEmptyAndFolderAreNamed)
{
    const std::string gz = write("scan.nrrd", gzip("NRRD0004\n"));
    EXPECT_EQ(test::error_of([&] { (void)read_nrrd(gz); }),
              gz + ": not a NRRD file: starts with binary data, expected the magic NRRD0001 to NRRD0005");
    expect_refused(write("empty.nrrd", ""), ": is empty");
    std::filesystem::create_directories(path("folder.nhdr"));
    expect_refused(path("folder.nhdr"), ": is a folder, not a file");
    std::filesystem::create_directories(path("voxels.raw"));
    expect_refused(write("detached.nhdr", "NRRD0004\n" + k_short3 + "encoding: raw\ndata file: voxels.raw\n"),
                   "data file '" + path("voxels.raw") + "' is a folder, not a file");
}

TEST_F(NrrdReader, RefusesMissingOrMismatchedData)
{
    expect_refused(path("absent.nrrd"), "no such file");
    expect_refused(write("nofile.nhdr", "NRRD0004\n" + k_short3 + "encoding: raw\ndata file: nowhere.raw\n"),
                   "data file '" + path("nowhere.raw") + "' does not exist");
    expect_refused(write("list.nhdr", "NRRD0004\n" + k_short3 + "encoding: raw\ndata file: LIST\na.raw\n"), "LIST");
    expect_refused(write("pattern.nhdr", "NRRD0004\n" + k_short3 + "encoding: raw\ndata file: slice%03d.raw 1 3 1\n"),
                   "numbered pattern");
    expect_refused(write("short.nrrd", nrrd(k_short3 + "encoding: raw\n", le16({1, 2}))), "truncated");
    expect_refused(write("long.nrrd", nrrd(k_short3 + "encoding: raw\n", le16({1, 2, 3, 4}))),
                   "the header does not describe this data");
    expect_refused(write("zip.nrrd", nrrd(k_short3 + "encoding: gzip\n", "not gzip data")), "corrupt compressed data");
    expect_refused(write("ziplen.nrrd", nrrd(k_short3 + "encoding: gzip\n", gzip(le16({1, 2})))), "holds 4 bytes");
    expect_refused(write("zipskip.nrrd", nrrd(k_short3 + "encoding: gzip\nbyte skip: -1\n", gzip(le16({1, 2, 3})))),
                   "raw encoding only");
    expect_refused(write("lines.nrrd", nrrd(k_short3 + "encoding: raw\nline skip: 3\n", "one line\n")),
                   "'line skip' passes the end");
}

TEST_F(NrrdReader, RefusesHugeDimensionsBeforeAllocating)
{
    expect_refused(
        write("huge.nrrd", nrrd("type: float\ndimension: 3\nsizes: 4096 4096 4096\nendian: little\nencoding: raw\n")),
        "memory limit");
    expect_refused(write("overflow.nrrd", nrrd("type: uchar\ndimension: 3\nsizes: 4294967296 4294967296 4294967296\n"
                                               "encoding: raw\n")),
                   "overflow");
    const std::uint64_t saved = memory_limit_bytes();
    set_memory_limit_bytes(1024);
    expect_refused(
        write("limit.nrrd", nrrd("type: short\ndimension: 3\nsizes: 32 32 1\nendian: little\nencoding: gzip\n",
                                 gzip(std::string(2048, '\0')))),
        "memory limit");
    set_memory_limit_bytes(saved);
}

} // namespace
} // namespace vox::io
