// 3D Slicer segmentations in and out. In: a .seg.nrrd that tests/io/write_segmentation.py writes
// from the liver, as Slicer 5 writes them (three named, coloured segments in two layers, two
// overlapping), with the voxel counts it computed. Out: what write_label_map writes is read by a
// parser of this test's own, written from Slicer's format description (the "Segmentation labelmap
// representation" page: NRRD header fields, "Segment<N>_<key>:=value" pairs, gzip data), not by
// the project's NRRD reader.

#include "io/label_map_writer.hpp"
#include "io/object_import.hpp"
#include "io/segmentation.hpp"

#include "core/error.hpp"
#include "core/label_palette.hpp"
#include "test_support.hpp"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>
#include <zlib.h>

#include <array>
#include <fstream>
#include <set>
#include <iterator>
#include <map>
#include <sstream>

using namespace vox::io;
using vox::test::expect_refused;
using vox::test::ScratchDir;

namespace {

const std::string k_liver = VOX_SOURCE_DIR "/data/liver.inr.gz";

/// Writes the test segmentation into `dir` and returns its path; its counts are beside it.
std::string write_segmentation(const ScratchDir& dir)
{
    const std::string out = dir.path("liver3.seg.nrrd");
    vox::test::run_python(VOX_SOURCE_DIR "/tests/io/write_segmentation.py", {k_liver, out});
    return out;
}

nlohmann::json counts_of(const std::string& seg) { return nlohmann::json::parse(std::ifstream(seg + ".counts.json")); }

/// What this test reads of a .seg.nrrd: the header's fields and pairs, and the voxels (uint8 or
/// int16, one layer, gzip).
struct SlicerFile {
    std::map<std::string, std::string> fields, pairs;
    std::vector<int> voxels;
};

SlicerFile parse_slicer(const std::string& path)
{
    std::ifstream in(path, std::ios::binary);
    const std::string bytes{std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
    SlicerFile f;
    std::size_t pos = bytes.find('\n') + 1; // past "NRRD0004"
    for (;;) {
        const std::size_t end = bytes.find('\n', pos);
        const std::string line = bytes.substr(pos, end - pos);
        pos = end + 1;
        if (line.empty()) break;
        if (line[0] == '#') continue;
        if (const auto kv = line.find(":="); kv != std::string::npos && kv < line.find(": "))
            f.pairs[line.substr(0, kv)] = line.substr(kv + 2);
        else
            f.fields[line.substr(0, line.find(": "))] = line.substr(line.find(": ") + 2);
    }
    EXPECT_EQ(f.fields["encoding"], "gzip");
    z_stream z{};
    inflateInit2(&z, 15 + 32);
    std::vector<unsigned char> raw(64u << 20);
    z.next_in = reinterpret_cast<Bytef*>(const_cast<char*>(bytes.data() + pos));
    z.avail_in = static_cast<uInt>(bytes.size() - pos);
    z.next_out = raw.data();
    z.avail_out = static_cast<uInt>(raw.size());
    EXPECT_EQ(inflate(&z, Z_FINISH), Z_STREAM_END);
    raw.resize(z.total_out);
    inflateEnd(&z);
    const bool two_bytes = f.fields["type"] == "int16";
    for (std::size_t i = 0; i + (two_bytes ? 1 : 0) < raw.size(); i += two_bytes ? 2 : 1)
        f.voxels.push_back(two_bytes ? static_cast<std::int16_t>(raw[i] | (raw[i + 1] << 8)) : raw[i]);
    return f;
}

} // namespace

TEST(Segmentation, SegmentsAreReadWithNamesColoursLayersAndLabelValues)
{
    const ScratchDir dir;
    const std::string seg = write_segmentation(dir);
    const std::vector<Segment> all = read_segments(seg);
    ASSERT_EQ(all.size(), 3u);
    EXPECT_EQ(all[0].name, "liver");
    EXPECT_EQ(all[1].id, "Segment_2");
    EXPECT_EQ(all[1].label_value, 2);
    EXPECT_EQ(all[2].name, "tumor");
    EXPECT_EQ(all[2].layer, 1);
    EXPECT_TRUE(all[1].color.isApprox(Eigen::Vector3d(0.0, 0.59, 0.81)));
    EXPECT_EQ(all[0].tags, "Segmentation.Status:inprogress|");
}

TEST(Segmentation, ASegmentWithoutALabelValueIsReadAsValueOneAndNamedInAWarning)
{
    // The tumor (alone in its layer, value 1) with its LabelValue key taken out, as Slicer before
    // 4.11 wrote it: the same voxels, and a warning that names it.
    const ScratchDir dir;
    const std::string seg = write_segmentation(dir);
    std::string bytes;
    {
        std::ifstream in(seg, std::ios::binary);
        bytes.assign(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
    }
    const std::string key = "Segment2_LabelValue:=1\n";
    const auto at = bytes.find(key);
    ASSERT_NE(at, std::string::npos);
    bytes.erase(at, key.size());
    const std::string old = dir.path("old.seg.nrrd");
    std::ofstream(old, std::ios::binary) << bytes;
    ::testing::internal::CaptureStderr();
    const std::vector<Segment> all = read_segments(old);
    const std::string warned = ::testing::internal::GetCapturedStderr();
    EXPECT_NE(warned.find("old.seg.nrrd: segment 'tumor' has no Segment2_LabelValue: its voxels are read as those of value 1 in its layer"),
              std::string::npos)
        << warned;
    EXPECT_EQ(warned.find("'liver'"), std::string::npos) << warned;
    ASSERT_EQ(all.size(), 3u);
    EXPECT_EQ(all[2].label_value, 1);
    EXPECT_EQ(read_segmentation(old, {"tumor"}).active_voxel_count(), counts_of(seg)["tumor"].get<std::uint64_t>());
}

TEST(Segmentation, SegmentsPickedByNameTakeLabelsInOrderAndTheLaterWinsWhereTheyOverlap)
{
    const ScratchDir dir;
    const std::string seg = write_segmentation(dir);
    const nlohmann::json counts = counts_of(seg);
    ImportOptions pick;
    pick.selection.segments = {"liver", "tumor"};
    const auto histogram = import_object(seg, pick).label_histogram();
    EXPECT_EQ(histogram.at(1), counts["liver_outside_tumor"].get<std::uint64_t>());
    EXPECT_EQ(histogram.at(2), counts["tumor"].get<std::uint64_t>());

    pick.selection.segments = {"tumor", "Segment_1"}; // by ID; now the liver wins over the tumor inside it
    const auto reversed = import_object(seg, pick).label_histogram();
    EXPECT_EQ(reversed.count(1), 0u);
    EXPECT_EQ(reversed.at(2), counts["liver"].get<std::uint64_t>());

    const auto every = import_object(seg, {}).label_histogram(); // all three, in file order
    EXPECT_EQ(every.at(2), counts["vessels"].get<std::uint64_t>());
    EXPECT_EQ(every.at(3), counts["tumor"].get<std::uint64_t>());

    pick.selection.segments = {"spleen"};
    expect_refused([&] { (void)import_object(seg, pick); }, seg,
                   "has no segment named 'spleen' (its segments: liver (Segment_1), vessels (Segment_2), tumor (Segment_3))");
    ImportOptions label;
    label.selection.labels = {1};
    expect_refused([&] { (void)import_object(seg, label); }, seg, "is selected by segment");
    pick.selection.segments = {"liver"};
    expect_refused([&] { (void)import_object(k_liver, pick); }, k_liver, "--segment picks segments of a 3D Slicer segmentation");
}

TEST(Segmentation, WrittenBackItKeepsTheGridNamesColoursAndVoxels)
{
    const ScratchDir dir;
    const std::string seg = write_segmentation(dir);
    ImportOptions pick;
    pick.selection.segments = {"liver", "tumor"};
    const vox::grid::LabelGrid labels = import_object(seg, pick);
    const std::string out = dir.path("back.seg.nrrd");
    write_label_map(labels, out);

    const SlicerFile in = parse_slicer(seg), back = parse_slicer(out);
    EXPECT_EQ(back.fields.at("dimension"), "3");
    EXPECT_EQ(back.fields.at("space"), "left-posterior-superior");
    const std::string sizes = in.fields.at("sizes").substr(2); // the input's without its layer axis
    EXPECT_EQ(back.fields.at("sizes"), sizes);
    // The same directions and origin, as numbers.
    const auto numbers = [](std::string text) {
        for (char& c : text)
            if (c == '(' || c == ')' || c == ',') c = ' ';
        std::istringstream s(text);
        std::vector<double> out;
        for (std::string w; s >> w;)
            if (w != "none") out.push_back(std::stod(w));
        return out;
    };
    const std::vector<double> a = numbers(in.fields.at("space directions")), b = numbers(back.fields.at("space directions"));
    ASSERT_EQ(a.size(), 9u);
    ASSERT_EQ(b.size(), 9u);
    for (std::size_t i = 0; i < 9; ++i) EXPECT_NEAR(a[i], b[i], 1e-9);
    const std::vector<double> o1 = numbers(in.fields.at("space origin")), o2 = numbers(back.fields.at("space origin"));
    for (std::size_t i = 0; i < 3; ++i) EXPECT_NEAR(o1[i], o2[i], 1e-9);

    // Segment 0 is the liver as label 1, segment 1 the tumor as label 2, with their names,
    // IDs and colours.
    EXPECT_EQ(back.pairs.at("Segmentation_MasterRepresentation"), "Binary labelmap");
    EXPECT_EQ(back.pairs.at("Segment0_Name"), "liver");
    EXPECT_EQ(back.pairs.at("Segment0_ID"), "Segment_1");
    EXPECT_EQ(back.pairs.at("Segment0_LabelValue"), "1");
    EXPECT_EQ(back.pairs.at("Segment1_Name"), "tumor");
    EXPECT_EQ(back.pairs.at("Segment1_ID"), "Segment_3");
    EXPECT_EQ(back.pairs.at("Segment1_LabelValue"), "2");
    EXPECT_EQ(back.pairs.at("Segment1_Layer"), "0");
    EXPECT_EQ(numbers(back.pairs.at("Segment1_Color")), numbers(in.pairs.at("Segment2_Color")));
    EXPECT_EQ(back.pairs.count("Segment2_ID"), 0u);

    // The voxels: the input's layers combined, the tumor over the liver.
    ASSERT_EQ(back.voxels.size() * 2, in.voxels.size());
    std::size_t different = 0;
    for (std::size_t n = 0; n < back.voxels.size(); ++n) {
        const int liver = in.voxels[2 * n] == 1, tumor = in.voxels[2 * n + 1] == 1;
        if (back.voxels[n] != (tumor ? 2 : liver ? 1 : 0)) ++different;
    }
    EXPECT_EQ(different, 0u);
}

TEST(Segmentation, AVolumeWrittenBackCoversTheScansWholeGridAndLabelsWithoutSegmentsGetNamesAndColours)
{
    // The liver's voxels of label 127 only: the scan's whole grid is written, so that the file lays
    // over the scan in Slicer with no registration.
    const ScratchDir dir;
    ImportOptions pick;
    pick.selection.labels = {127};
    const vox::grid::LabelGrid labels = import_object(k_liver, pick);
    write_label_map(labels, dir.path("vessels.seg.nrrd"));
    const SlicerFile back = parse_slicer(dir.path("vessels.seg.nrrd"));
    EXPECT_EQ(back.fields.at("sizes"), "438 353 165");
    EXPECT_EQ(back.pairs.at("Segment0_Name"), "label 127");
    EXPECT_EQ(back.pairs.at("Segment0_LabelValue"), "127");
    // Coloured as Slicer colours label 127 (salivary glands, 70 163 117): the one palette.
    std::istringstream color(back.pairs.at("Segment0_Color"));
    Eigen::Vector3d rgb;
    color >> rgb.x() >> rgb.y() >> rgb.z();
    EXPECT_TRUE(rgb.isApprox(Eigen::Vector3d(70, 163, 117) / 255.0, 1e-5)) << back.pairs.at("Segment0_Color");
    std::size_t count = 0;
    for (const int v : back.voxels) count += v == 127;
    EXPECT_EQ(count, 314086u);
    expect_refused([&] { write_label_map(labels, dir.path("x.mha")); }, dir.path("x.mha"), "a label map is written as");
}

TEST(LabelPalette, IsSlicersGenericAnatomyTableAndGivesEveryLabelAColourOfIt)
{
    // Rows of data/palette/GenericAnatomyColors.txt as Slicer has them.
    EXPECT_TRUE(vox::label_color(1).isApprox(Eigen::Vector3d(128, 174, 128) / 255.0)); // tissue
    EXPECT_TRUE(vox::label_color(2).isApprox(Eigen::Vector3d(241, 214, 145) / 255.0)); // bone
    EXPECT_TRUE(vox::label_color(14).isApprox(Eigen::Vector3d(250, 250, 210) / 255.0)); // white matter
    EXPECT_TRUE(vox::label_color(309).isApprox(Eigen::Vector3d(205, 205, 100) / 255.0)); // cyst, the last
    EXPECT_TRUE(vox::label_color(0).isApprox(vox::label_color(1)));                      // unlabelled: tissue
    // Beyond the table: one of its colours, the same every time, neighbours told apart.
    std::set<std::array<double, 3>> table;
    for (std::int32_t l = 1; l <= 309; ++l) table.insert({vox::label_color(l).x(), vox::label_color(l).y(), vox::label_color(l).z()});
    for (const std::int32_t l : {310, 311, 1000, -5, 65535}) {
        const Eigen::Vector3d c = vox::label_color(l);
        EXPECT_TRUE(table.count({c.x(), c.y(), c.z()})) << l;
        EXPECT_EQ(c, vox::label_color(l));
    }
    EXPECT_NE(vox::label_color(310), vox::label_color(311));
}
