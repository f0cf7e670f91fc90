// The tool-mesh sweep catches what surface points cannot: a tool thinner than the gaps between the
// surface's vertices passing through a face (vertex-face) or across an edge (edge-edge) between
// them, and stops 1 um short of the touch; it leaves alone motions that touch nothing and
// triangles already in the penalty contact.

#include "contact/tool_sweep.hpp"

#include <gtest/gtest.h>

using namespace vox::contact;
using Eigen::Vector3d;

namespace {

/// A 20 x 20 mm square in z = 0 made of two triangles: four points 20 mm apart.
SurfacePoints coarse_square()
{
    SurfacePoints s(4);
    const Vector3d corners[4] = {{-10, -10, 0}, {10, -10, 0}, {10, 10, 0}, {-10, 10, 0}};
    for (const Vector3d& c : corners) {
        s.positions_mm[s.count] = c;
        s.normals[s.count] = Vector3d::UnitZ();
        s.areas_mm2[s.count] = 100.0;
        ++s.count;
    }
    s.triangles = {{0, 1, 2}, {0, 2, 3}};
    const std::span<const Vector3d> p(s.positions_mm.data(), s.count);
    s.triangle_tree.rebuild(p, p, s.triangles);
    s.t_s = 0.0;
    return s;
}

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
    // The ball's own mesh (inscribed: its lowest part 0.19 - 0.2 mm below the centre) reaches z = 0.
    const double z_stop = 3.0 - 6.0 * t;
    EXPECT_GT(z_stop, 0.185);
    EXPECT_LT(z_stop, 0.2015); // 1 um short of the touch
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
    // Above the square, beside it, and moving away from it.
    EXPECT_EQ(sweep.first_stop(at(needle, {1, 2, 3}), at(needle, {5, 5, 1}), square), 1.0);
    EXPECT_EQ(sweep.first_stop(at(needle, {15, 2, 3}), at(needle, {15, 2, -3}), square), 1.0);
    EXPECT_EQ(sweep.first_stop(at(needle, {1, 2, 0.5}), at(needle, {1, 2, 3}), square), 1.0);
    EXPECT_FALSE(sweep.stopped_by_mesh());
}

TEST(ToolSweep, MovesShorterThanTheMarginAreLeftToThePointContact)
{
    // 0.05 mm a tick with a 0.1 mm margin: the needle's tip may enter the face between points, as
    // a blade's edge must to reach the points it cuts.
    const ToolShape needle = ToolShape::sphere(0.2);
    const SurfacePoints square = coarse_square();
    ToolSweep sweep(needle, 0.1, square.capacity());
    EXPECT_EQ(sweep.first_stop(at(needle, {1, 2, 0.22}), at(needle, {1, 2, 0.17}), square), 1.0);
    EXPECT_FALSE(sweep.stopped_by_mesh());
}

TEST(ToolSweep, TrianglesInThePenaltyContactAreLeftToIt)
{
    // A broad ball pressing on a corner point: that point is in the contact, so its triangles are
    // the penalty's and the tool may go on pressing.
    const ToolShape ball = ToolShape::sphere(3.0);
    const SurfacePoints square = coarse_square();
    ToolSweep sweep(ball, 0.5, square.capacity());
    EXPECT_EQ(sweep.first_stop(at(ball, {-10, -10, 3.0}), at(ball, {-10, -10, 1.5}), square), 1.0); // a jump of 1.5 mm
    EXPECT_FALSE(sweep.stopped_by_mesh());
}
