// One stroke, one cut: a blade drawn through an object that moves while it is cut opens one
// sheet, with no second sheet beside it and no sliver falling away, on both methods (the branched
// grid in separate mode loses no voxel either). Straight and curved strokes, continuous and
// two-phase, through objects held at both ends, sagging, swinging and drooping. CI runs a fixed
// sample; `ctest -L long` runs a longer random one (one_sheet_long_test.cpp).

#include "stroke_scenes.hpp"

#include <random>

namespace vox::sim {
namespace {

using namespace test;

class OneSheet : public ::testing::TestWithParam<io::SolverType> {};

TEST_P(OneSheet, ARodHeldAtBothEndsCutStraightDown)
{
    const SheetCount n = run_and_count(rod_stroke({50.3, 0, 0, true}, 1e5, k_both_ends, false, "rod.json"), GetParam(), "rod.json");
    expect_one_sheet(n);
    EXPECT_EQ(n.pieces, 2u);
}

TEST_P(OneSheet, RandomStraightStrokesThroughASaggingRodEachOpenOneSheet)
{
    // A fixed sample of strokes: where along the rod, the blade's plane turned about the vertical
    // and then tilted about the rod's axis, the rod soft enough to sag and swing as it is cut;
    // each blade edge first along its own plane, then the same blades straight down, held at a
    // slant to the way they move.
    std::mt19937 rng(21);
    std::uniform_real_distribution<double> along(30.0, 70.0), turn(-0.35, 0.35), tilt(-0.5, 0.5);
    std::vector<StraightStroke> drawn(GetParam() == io::SolverType::dbg ? 4 : 2);
    for (StraightStroke& d : drawn) d = {along(rng), turn(rng), tilt(rng), true};
    for (bool along_plane : {true, false})
        for (StraightStroke s : drawn) {
            s.along_plane = along_plane;
            SCOPED_TRACE(testing::Message() << "stroke at x " << s.x << ", turned " << s.yaw << ", tilted " << s.roll << (along_plane ? ", along its plane" : ", straight down"));
            const SheetCount n = run_and_count(rod_stroke(s, 5e4, k_both_ends, false, "random_rod.json"), GetParam(), "random_rod.json");
            expect_one_sheet(n);
        }
}

TEST_P(OneSheet, ATwoPhaseStrokeThroughARodHeldAtBothEnds)
{
    const SheetCount n = run_and_count(rod_stroke({48.7, 0.2, 0.3, false}, 5e4, k_both_ends, true, "two_phase_rod.json"), GetParam(),
                                             "two_phase_rod.json");
    // The rod is held while the blade marks, and the marked path is cut once, where the pressure
    // first breaks in; the blade only pushes after that.
    EXPECT_GT(n.faces, 0u);
    expect_one_sheet(n);
}

TEST_P(OneSheet, ARodHeldAtOneEndCutWhileItSwingsDown)
{
    // Released straight, the cantilever falls and swings under gravity as the blade comes down.
    const SheetCount n = run_and_count(rod_stroke({60.4, -0.1, 0.2, false}, 1e6, k_one_end, false, "swinging_rod.json"), GetParam(),
                                             "swinging_rod.json");
    EXPECT_GT(n.faces, 0u);
    expect_one_sheet(n);
}

TEST_P(OneSheet, ACurvedStrokeThroughAPlateIsOneContinuousSheet)
{
    const SheetCount n = run_and_count(curved_stroke(25.0, 1.0, 0.3, "curved_plate.json"), GetParam(), "curved_plate.json");
    expect_one_sheet(n);
    EXPECT_EQ(n.pieces, 1u) << "an open arc leaves the plate one piece";
}

TEST_P(OneSheet, ADroopingSlabCutByATiltedBlade)
{
    const SheetCount n = run_and_count(drooping_slab(20.0 * M_PI / 180.0, 45.3, 3e5, "slab.json"), GetParam(), "slab.json");
    // Branched grid: before the carry across the blade's plane was held for the stroke, 3,291
    // faces, 2,390 parallel pairs, 29 pieces of which 9 slivers. Before the section reached past
    // what the edge presses: 73 faces (the slab bent away under the blade). Now about 275 of the
    // section's 320: the blade's edge slopes, and the far piece, hanging by the last corner,
    // swings under it and is pressed on its top, away from the cut.
    if (GetParam() == io::SolverType::dbg) EXPECT_GT(n.faces, 200u) << "it cut most of the way through the slab";
    EXPECT_GT(n.faces, 0u);
    expect_one_sheet(n);
}

TEST_P(OneSheet, TheBundledLiverIncisionIsOneSheetLeavingOnePiece)
{
    const SheetCount n = run_and_count(io::load_scene(VOX_SOURCE_DIR "/data/scenes/liver_incision.json"), GetParam(), "liver_incision.json");
    if (GetParam() == io::SolverType::dbg) {
        // A 50 mm incision about 8 mm deep: about 400 mm^2 of 0.62 x 0.62 mm faces, and up to one
        // contact zone (1 mm) more under the edge (about 500 mm^2 are opened).
        const double area_mm2 = static_cast<double>(n.faces) * 0.617188 * 0.617188;
        EXPECT_GT(area_mm2, 250.0);
        EXPECT_LT(area_mm2, 600.0);
    }
    expect_one_sheet(n);
    EXPECT_EQ(n.pieces, 1u) << "an incision leaves the liver one piece";
}

INSTANTIATE_TEST_SUITE_P(Methods, OneSheet, ::testing::Values(io::SolverType::dbg, io::SolverType::isxfem),
                         [](const auto& info) { return std::string(info.param == io::SolverType::dbg ? "dbg" : "isxfem"); });

} // namespace
} // namespace vox::sim
