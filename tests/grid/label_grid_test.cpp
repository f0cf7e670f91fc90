#include "grid/label_grid.hpp"

#include "core/error.hpp"
#include "core/memory_limit.hpp"

#include <Eigen/Geometry>

#include <gtest/gtest.h>

#include <fstream>

namespace fs = std::filesystem;
using vox::grid::LabelGrid;

namespace {
Eigen::Matrix4d rotated_transform()
{
    // Anisotropic spacing, a rotation about z by 30 degrees and an offset: nothing axis-aligned.
    Eigen::Matrix4d t = Eigen::Matrix4d::Identity();
    const double c = std::cos(M_PI / 6), s = std::sin(M_PI / 6);
    Eigen::Matrix3d r;
    r << c, -s, 0, s, c, 0, 0, 0, 1;
    t.topLeftCorner<3, 3>() = r * Eigen::Vector3d(0.5, 0.75, 1.25).asDiagonal();
    t.topRightCorner<3, 1>() = Eigen::Vector3d(-10, 20, 5);
    return t;
}
} // namespace

TEST(LabelGrid, SetGetCountAndHistogram)
{
    LabelGrid g;
    g.set({0, 0, 0}, 3);
    g.set({-5, 2, 9}, 7);
    g.set({1, 1, 1}, 3);
    g.set({1, 1, 1}, 0); // deactivates
    EXPECT_EQ(g.get({0, 0, 0}), 3);
    EXPECT_EQ(g.get({-5, 2, 9}), 7);
    EXPECT_EQ(g.get({1, 1, 1}), 0);
    EXPECT_EQ(g.active_voxel_count(), 2u);
    const auto hist = g.label_histogram();
    EXPECT_EQ(hist.at(3), 1u);
    EXPECT_EQ(hist.at(7), 1u);
    const auto box = g.index_bounds();
    EXPECT_EQ(box.min, vox::grid::Coord(-5, 0, 0));
    EXPECT_EQ(box.max, vox::grid::Coord(0, 2, 9));
}

TEST(LabelGrid, TransformMapsVoxelCentres)
{
    const Eigen::Matrix4d t = rotated_transform();
    LabelGrid g(t);
    EXPECT_TRUE(g.index_to_world().isApprox(t, 1e-12));
    const Eigen::Vector3d ijk(2, -1, 3);
    EXPECT_TRUE(g.index_to_world(ijk).isApprox((t * ijk.homogeneous()).head<3>(), 1e-12));
    EXPECT_TRUE(g.voxel_size().isApprox(Eigen::Vector3d(0.5, 0.75, 1.25), 1e-12));
}

TEST(LabelGrid, SaveLoadRoundTripKeepsVoxelsTransformAndMetadata)
{
    const fs::path path = fs::path(::testing::TempDir()) / "roundtrip.vdb";
    LabelGrid g(rotated_transform());
    for (int i = 0; i < 20; ++i) g.set({i, i % 3, -i}, 1 + i % 4);
    g.set_metadata("source", "test");
    g.save(path);
    const LabelGrid r = LabelGrid::load(path);
    EXPECT_EQ(r.active_voxel_count(), 20u);
    for (int i = 0; i < 20; ++i) EXPECT_EQ(r.get({i, i % 3, -i}), 1 + i % 4);
    EXPECT_TRUE(r.index_to_world().isApprox(rotated_transform(), 1e-12));
    EXPECT_EQ(r.metadata("source"), "test");
}

TEST(LabelGrid, LoadRefusesMissingAndForeignFiles)
{
    EXPECT_THROW((void)LabelGrid::load("/nonexistent/x.vdb"), vox::InputError);
    const fs::path junk = fs::path(::testing::TempDir()) / "junk.vdb";
    std::ofstream(junk) << "not a vdb file";
    try {
        (void)LabelGrid::load(junk);
        FAIL();
    } catch (const vox::InputError& e) {
        EXPECT_NE(std::string(e.what()).find(junk.string()), std::string::npos);
    }
}

TEST(LabelGrid, CorruptFilesAreReadInAChildAndRefusedNamingTheFile)
{
    // Fuzzing found these: OpenVDB's reader crashed on the first, grew to gigabytes on the next
    // two, spun for ever on the fourth and overran the heap on the fifth. Read in a child
    // process, each is one message.
    const std::uint64_t saved = vox::memory_limit_bytes();
    vox::set_memory_limit_bytes(std::uint64_t{512} << 20);
    const std::vector<std::pair<std::string, std::string>> expected = {
        // Its garbage sends the reader different ways from run to run (the memory limit, or an
        // unknown map type it names): any of them is a refusal.
        {"vdb_segfault.vdb", "not a readable OpenVDB file"},
        {"vdb_hang_memory_a.vdb", "reading it needs more than the memory limit of 512 MiB"},
        {"vdb_hang_memory_b.vdb", "reading it needs more than the memory limit of 512 MiB"},
        {"vdb_hang_spin.vdb", "OpenVDB's reader did not finish within 3 s"},
        // Read "cleanly" by the child once, then aborted this process ("corrupted size vs.
        // prev_size") when it read the file itself: it now reads only what OpenVDB wrote.
        {"vdb_heap_corruption.vdb", "not a readable OpenVDB file"},
        {"vdb_singular_transform.vdb", "its grid transform is unusable"}, // the vdb fuzz target's
    };
    for (const auto& [name, reason] : expected) {
        SCOPED_TRACE(name);
        const std::string file = VOX_TEST_DATA_DIR "/bad/" + name;
        try {
            (void)LabelGrid::load(file);
            ADD_FAILURE() << "loaded";
        } catch (const vox::InputError& e) {
            const std::string message = e.what();
            EXPECT_EQ(message.rfind(file + ": ", 0), 0u) << message;
            EXPECT_NE(message.find(reason), std::string::npos) << message;
            EXPECT_EQ(message.find('\n'), std::string::npos) << "one line";
            EXPECT_LT(message.size(), 400u) << message;
        }
    }
    vox::set_memory_limit_bytes(saved);
}

TEST(LabelGrid, CloneIsIndependent)
{
    LabelGrid g;
    g.set({1, 2, 3}, 5);
    LabelGrid c = g.clone();
    c.set({1, 2, 3}, 0);
    EXPECT_EQ(g.get({1, 2, 3}), 5);
    EXPECT_EQ(c.active_voxel_count(), 0u);
}
