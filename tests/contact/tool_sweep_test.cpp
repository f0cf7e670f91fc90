// The tool-mesh sweep catches what surface points cannot: a tool thinner than the gaps between the
// surface's vertices passing through a face (vertex-face) or across an edge (edge-edge) between
// them, and stops 1 um short of the touch; it leaves alone motions that touch nothing and
// triangles already in the penalty contact.

#include "contact/tool_sweep.hpp"
#include "surface_snapshots.hpp"

#include <gtest/gtest.h>

using namespace vox::contact;
using Eigen::Vector3d;
using vox::test::coarse_square;

namespace {

PlacedShape at(const ToolShape& shape, const Vector3d& p) { return {&shape, p, Eigen::Quaterniond::Identity()}; }

} // namespace

TEST(ToolSweep, ANeedleThroughAFaceBetweenPointsStopsAtTheFace)
{
    // A 0.2 mm ball (pushing radius 0.3 mm) falls from z = 3 to z = -3 through the square's middle:
    // no point is touched at either end, nor in between.
    const ToolShape needle = ToolShape::sphere(0.2);
    const SurfacePoints square = coarse_square();
    ToolSweep sweep(needle, 0.1, square.capacity());
    const double t = sweep.first_stop(at(needle, {1, 2, 3}), at(needle, {1, 2, -3}), square);
    EXPECT_TRUE(sweep.stopped_by_mesh());
    // The ball's own mesh (inscribed: its lowest part 0.19 - 0.2 mm below the centre) reaches z = 0;
    // the stop is found to a quarter of the margin (0.025 mm), and 1 um short of it.
    const double z_stop = 3.0 - 6.0 * t;
    EXPECT_GT(z_stop, 0.185);
    EXPECT_LT(z_stop, 0.2 + 0.025 + 0.0011);
}

TEST(ToolSweep, ARodAcrossTheEdgesIsCaughtByTheEdgeTest)
{
    // A rod longer than the square (its ends beyond it) and thinner than the gaps drops through
    // it: no tool vertex meets a face and no surface point meets the rod; only its edges cross
    // the square's edges.
    const ToolShape rod = ToolShape::box({30, 0.2, 0.2});
    const SurfacePoints square = coarse_square();
    ToolSweep sweep(rod, 0.0, square.capacity());
    const double t = sweep.first_stop(at(rod, {0, 3, 2}), at(rod, {0, 3, -2}), square);
    EXPECT_TRUE(sweep.stopped_by_mesh());
    const double z_stop = 2.0 - 4.0 * t; // the rod's underside (0.1 mm below its centre) at z = 0
    EXPECT_GT(z_stop, 0.099);
    EXPECT_LT(z_stop, 0.11);
}

TEST(ToolSweep, MotionsThatTouchNothingGoAllTheWay)
{
    const ToolShape needle = ToolShape::sphere(0.2);
    const SurfacePoints square = coarse_square();
    ToolSweep sweep(needle, 0.1, square.capacity());
    // Above the square, beside it, and moving away from it: the mesh test runs and finds nothing.
    for (const auto& [from, to] : {std::pair{Vector3d(1, 2, 3), Vector3d(5, 5, 1)}, std::pair{Vector3d(15, 2, 3), Vector3d(15, 2, -3)},
                                   std::pair{Vector3d(1, 2, 0.5), Vector3d(1, 2, 3)}}) {
        EXPECT_EQ(sweep.first_stop(at(needle, from), at(needle, to), square), 1.0);
        EXPECT_TRUE(sweep.swept_mesh());
        EXPECT_FALSE(sweep.stopped_by_mesh());
    }
}

TEST(ToolSweep, MovesShorterThanTheMarginAreLeftToThePointContact)
{
    // 0.05 mm a tick with a 0.1 mm margin: the needle's tip may enter the face between points, as
    // a blade's edge must to reach the points it cuts.
    const ToolShape needle = ToolShape::sphere(0.2);
    const SurfacePoints square = coarse_square();
    ToolSweep sweep(needle, 0.1, square.capacity());
    EXPECT_EQ(sweep.first_stop(at(needle, {1, 2, 0.22}), at(needle, {1, 2, 0.17}), square), 1.0);
    EXPECT_FALSE(sweep.swept_mesh());
}

TEST(ToolSweep, TrianglesInThePenaltyContactAreLeftToIt)
{
    // A broad ball already pressing on a corner point when the tick starts: that point is in the
    // contact, so its triangles are the penalty's and the tool may go on pressing.
    const ToolShape ball = ToolShape::sphere(3.0);
    const SurfacePoints square = coarse_square();
    ToolSweep sweep(ball, 0.5, square.capacity());
    EXPECT_EQ(sweep.first_stop(at(ball, {-10, -10, 3.0}), at(ball, {-10, -10, 1.5}), square), 1.0); // a jump of 1.5 mm
    EXPECT_TRUE(sweep.swept_mesh());
    EXPECT_FALSE(sweep.stopped_by_mesh());
}

TEST(ToolSweep, AJabEndingDeepInTheObjectStopsAtTheSurface)
{
    // A blade jabbed 7 mm down through a wall of 1 mm triangles in one tick: it ends 4 mm deep
    // with its top face against the wall's points, so those points are in the contact at the end;
    // it must still stop where its lowest edge first meets the wall.
    const ToolShape blade = ToolShape::box({10, 0.5, 4});
    const SurfacePoints wall = vox::test::flat_wall(41, true);
    ToolSweep sweep(blade, 0.25, wall.capacity());
    const double t = sweep.first_stop(at(blade, {0.3, 0.3, 5}), at(blade, {0.3, 0.3, -2}), wall);
    EXPECT_TRUE(sweep.stopped_by_mesh());
    const double bottom = 5.0 - 7.0 * t - 2.0; // the blade's lower face, within a quarter margin above the wall
    EXPECT_GT(bottom, 0.0);
    EXPECT_LT(bottom, 0.25 / 4 + 0.0011);
}
