#include "io/tool_script.hpp"

#include "io/scene.hpp"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <Eigen/Geometry>

#include <cmath>
#include <numbers>
#include <stdexcept>

namespace {

using nlohmann::json;
using namespace vox::io;

constexpr double pi = std::numbers::pi;

/// A beam scene with three tools ("blade", "probe", "idle") and `script`.
Scene scene_with_script(const char* script)
{
    json doc = json::parse(R"({
        "object": {"phantom": {"shape": "beam"}},
        "tools": [
            {"name": "blade", "shape": "blade", "size_mm": [40, 1, 20]},
            {"name": "probe", "shape": "sphere", "radius_mm": 5},
            {"name": "idle", "shape": "scalpel"}
        ]
    })");
    doc["script"] = json::parse(script);
    return parse_scene(doc, "/tmp", "script.json");
}

TEST(ToolPose, MidpointPositionIsTheMean)
{
    const Scene s = scene_with_script(R"([
        {"t_s": 1, "tool": "blade", "position_mm": [0, 10, 30]},
        {"t_s": 3, "tool": "blade", "position_mm": [100, 20, -10]}
    ])");
    const ToolPose mid = tool_pose(s, 0, 2.0);
    EXPECT_TRUE(mid.placed);
    EXPECT_EQ(mid.position_mm, Eigen::Vector3d(50, 15, 10));
    EXPECT_EQ(mid.orientation.coeffs(), Eigen::Quaterniond::Identity().coeffs());
    const ToolPose quarter = tool_pose(s, 0, 1.5);
    EXPECT_TRUE(quarter.position_mm.isApprox(Eigen::Vector3d(25, 12.5, 20), 1e-15));
    // At the entries themselves, their positions exactly.
    EXPECT_EQ(tool_pose(s, 0, 1.0).position_mm, Eigen::Vector3d(0, 10, 30));
    EXPECT_EQ(tool_pose(s, 0, 3.0).position_mm, Eigen::Vector3d(100, 20, -10));
}

TEST(ToolPose, SlerpOfAQuarterTurnAboutZIsAnEighthTurnAtHalfTime)
{
    const Scene s = scene_with_script(R"([
        {"t_s": 0, "tool": "blade", "position_mm": [0, 0, 0], "orientation_wxyz": [1, 0, 0, 0]},
        {"t_s": 1, "tool": "blade", "position_mm": [0, 0, 0], "orientation_wxyz": [0.7071067811865476, 0, 0, 0.7071067811865476]}
    ])");
    const ToolPose half = tool_pose(s, 0, 0.5);
    ASSERT_TRUE(half.placed);
    const Eigen::Quaterniond expected(Eigen::AngleAxisd(pi / 4, Eigen::Vector3d::UnitZ()));
    EXPECT_NEAR(half.orientation.angularDistance(expected), 0.0, 1e-12);
    EXPECT_NEAR(half.orientation.norm(), 1.0, 1e-15);
    // The tool's x axis points at 45 degrees in the xy plane.
    const Eigen::Vector3d x = half.orientation * Eigen::Vector3d::UnitX();
    EXPECT_TRUE(x.isApprox(Eigen::Vector3d(std::sqrt(0.5), std::sqrt(0.5), 0), 1e-12)) << x.transpose();
    // Constant angular speed: the angle from the start grows linearly with time.
    for (const double t : {0.0, 0.1, 0.25, 0.6, 0.9, 1.0}) {
        SCOPED_TRACE(t);
        EXPECT_NEAR(tool_pose(s, 0, t).orientation.angularDistance(Eigen::Quaterniond::Identity()), t * pi / 2, 1e-12);
    }
}

TEST(ToolPose, SlerpTakesTheShorterWay)
{
    // q and -q are the same rotation: a quarter turn about z written with w < 0 is still reached
    // through an eighth turn, not the long way round.
    const Scene s = scene_with_script(R"([
        {"t_s": 0, "tool": "blade", "position_mm": [0, 0, 0]},
        {"t_s": 1, "tool": "blade", "position_mm": [0, 0, 0], "orientation_wxyz": [-1, 0, 0, -1]}
    ])");
    const Eigen::Quaterniond expected(Eigen::AngleAxisd(pi / 4, Eigen::Vector3d::UnitZ()));
    EXPECT_NEAR(tool_pose(s, 0, 0.5).orientation.angularDistance(expected), 0.0, 1e-12);
}

TEST(ToolPose, BeforeTheFirstAndAfterTheLastEntryTheToolStays)
{
    const Scene s = scene_with_script(R"([
        {"t_s": 1, "tool": "blade", "position_mm": [1, 2, 3], "orientation_wxyz": [0, 1, 0, 0]},
        {"t_s": 2, "tool": "blade", "position_mm": [4, 5, 6], "orientation_wxyz": [0, 0, 1, 0]}
    ])");
    for (const double t : {0.0, 0.5, 1.0}) {
        SCOPED_TRACE(t);
        const ToolPose p = tool_pose(s, 0, t);
        EXPECT_TRUE(p.placed);
        EXPECT_EQ(p.position_mm, Eigen::Vector3d(1, 2, 3));
        EXPECT_EQ(p.orientation.coeffs(), Eigen::Vector4d(1, 0, 0, 0)); // x, y, z, w
    }
    for (const double t : {2.0, 2.5, 1e6}) {
        SCOPED_TRACE(t);
        const ToolPose p = tool_pose(s, 0, t);
        EXPECT_TRUE(p.placed);
        EXPECT_EQ(p.position_mm, Eigen::Vector3d(4, 5, 6));
        EXPECT_EQ(p.orientation.coeffs(), Eigen::Vector4d(0, 1, 0, 0));
    }
}

TEST(ToolPose, ASingleEntryHoldsForAllTime)
{
    const Scene s = scene_with_script(R"([{"t_s": 2, "tool": "probe", "position_mm": [7, 8, 9]}])");
    for (const double t : {0.0, 2.0, 5.0}) {
        const ToolPose p = tool_pose(s, 1, t);
        EXPECT_TRUE(p.placed);
        EXPECT_EQ(p.position_mm, Eigen::Vector3d(7, 8, 9));
    }
}

TEST(ToolPose, AToolWithoutEntriesIsNotPlaced)
{
    const Scene s = scene_with_script(R"([{"t_s": 0, "tool": "blade", "position_mm": [0, 0, 0]}])");
    const ToolPose p = tool_pose(s, 2, 0.0);
    EXPECT_FALSE(p.placed);
    EXPECT_TRUE(p.position_mm.array().isNaN().all()); // as `voxsculpt run` reports an unplaced tool
    EXPECT_EQ(p.orientation.coeffs(), Eigen::Quaterniond::Identity().coeffs());

    const Scene empty = scene_with_script("[]");
    EXPECT_FALSE(tool_pose(empty, 0, 1.0).placed);
}

TEST(ToolPose, OtherToolsEntriesAreSkipped)
{
    // The probe's entries sit between the blade's; the blade moves from its first entry to its
    // second as if they were not there, and the reverse.
    const Scene s = scene_with_script(R"([
        {"t_s": 0, "tool": "blade", "position_mm": [0, 0, 0]},
        {"t_s": 0.5, "tool": "probe", "position_mm": [100, 100, 100], "orientation_wxyz": [0, 0, 0, 1]},
        {"t_s": 1, "tool": "probe", "position_mm": [200, 200, 200]},
        {"t_s": 2, "tool": "blade", "position_mm": [20, 0, -40], "orientation_wxyz": [0.7071067811865476, 0, 0, 0.7071067811865476]}
    ])");
    const ToolPose blade = tool_pose(s, 0, 1.0);
    EXPECT_EQ(blade.position_mm, Eigen::Vector3d(10, 0, -20));
    EXPECT_NEAR(blade.orientation.angularDistance(Eigen::Quaterniond(Eigen::AngleAxisd(pi / 4, Eigen::Vector3d::UnitZ()))),
                0.0, 1e-12);
    const ToolPose probe = tool_pose(s, 1, 0.75);
    EXPECT_EQ(probe.position_mm, Eigen::Vector3d(150, 150, 150));
    // From a half turn about z back to identity: a quarter turn about z at the midpoint.
    EXPECT_NEAR(probe.orientation.angularDistance(Eigen::Quaterniond(Eigen::AngleAxisd(pi / 2, Eigen::Vector3d::UnitZ()))),
                0.0, 1e-12);
    EXPECT_EQ(tool_pose(s, 1, 0.0).position_mm, Eigen::Vector3d(100, 100, 100)); // the probe waits at its first
    EXPECT_EQ(tool_pose(s, 1, 3.0).position_mm, Eigen::Vector3d(200, 200, 200));
    EXPECT_FALSE(tool_pose(s, 2, 1.0).placed);
}

TEST(ToolPose, TwoEntriesAtOneTimeJumpAndTheLaterWinsFromThen)
{
    const Scene s = scene_with_script(R"([
        {"t_s": 0, "tool": "blade", "position_mm": [0, 0, 0]},
        {"t_s": 1, "tool": "blade", "position_mm": [10, 0, 0]},
        {"t_s": 1, "tool": "blade", "position_mm": [50, 0, 0], "orientation_wxyz": [0, 0, 0, 1]},
        {"t_s": 2, "tool": "blade", "position_mm": [60, 0, 0], "orientation_wxyz": [0, 0, 0, 1]}
    ])");
    // Before the jump the blade heads for the first of the two entries...
    EXPECT_EQ(tool_pose(s, 0, 0.5).position_mm, Eigen::Vector3d(5, 0, 0));
    EXPECT_TRUE(tool_pose(s, 0, 1.0 - 1e-9).position_mm.isApprox(Eigen::Vector3d(10, 0, 0), 1e-9));
    EXPECT_NEAR(tool_pose(s, 0, 1.0 - 1e-9).orientation.angularDistance(Eigen::Quaterniond::Identity()), 0.0, 1e-12);
    // ...at the jump's time it is at the second, and from there it goes on.
    const ToolPose at = tool_pose(s, 0, 1.0);
    EXPECT_EQ(at.position_mm, Eigen::Vector3d(50, 0, 0));
    EXPECT_EQ(at.orientation.coeffs(), Eigen::Vector4d(0, 0, 1, 0));
    EXPECT_EQ(tool_pose(s, 0, 1.5).position_mm, Eigen::Vector3d(55, 0, 0));
}

TEST(ToolPose, PositionsMatchTheRunCommandsInterpolationExactly)
{
    // `voxsculpt run` computes (1 - a) p0 + a p1; tool_pose must give the same doubles, so
    // switching to it changes no output.
    const Scene s = scene_with_script(R"([
        {"t_s": 0.0, "tool": "blade", "position_mm": [100, 5, 30]},
        {"t_s": 0.7, "tool": "blade", "position_mm": [100.3, 5.1, -10.7]}
    ])");
    for (int f = 0; f <= 100; ++f) {
        const double t = f * 0.01;
        const double a = t >= 0.7 ? 1.0 : t / 0.7;
        const Eigen::Vector3d expected =
            t >= 0.7 ? s.script[1].position_mm : ((1 - a) * s.script[0].position_mm + a * s.script[1].position_mm).eval();
        EXPECT_EQ(tool_pose(s, 0, t).position_mm, expected) << t;
    }
}

TEST(ToolPose, AToolIndexOutOfRangeIsAProgrammingError)
{
    const Scene s = scene_with_script("[]");
    EXPECT_THROW(static_cast<void>(tool_pose(s, 3, 0.0)), std::out_of_range);
}

} // namespace
