// Virtual coupling: in free space the proxy is the device and nothing is felt; against a wall the
// proxy stops where the coupling spring and the contact balance, and the user feels that force,
// pointing out of the wall, steady from tick to tick however stiff the contact.

#include "haptics/coupled_tool.hpp"

#include <gtest/gtest.h>

using namespace vox;

namespace {

/// A flat wall z <= 0 sampled on a 1 mm grid of 41 x 41 points, 1 mm^2 each, outward normal +z.
contact::SurfacePoints wall()
{
    contact::SurfacePoints s(41 * 41);
    for (int i = 0; i < 41; ++i)
        for (int j = 0; j < 41; ++j) {
            s.positions_mm[s.count] = Eigen::Vector3d(i - 20.0, j - 20.0, 0.0);
            s.normals[s.count] = Eigen::Vector3d::UnitZ();
            s.areas_mm2[s.count] = 1.0;
            ++s.count;
        }
    s.t_s = 0.0;
    return s;
}

haptics::DeviceState at(double z)
{
    haptics::DeviceState d;
    d.position_mm = Eigen::Vector3d(0, 0, z);
    return d;
}

} // namespace

TEST(CoupledTool, InFreeSpaceTheProxyIsTheDeviceAndNothingIsFelt)
{
    const contact::ToolShape ball = contact::ToolShape::sphere(2.0);
    haptics::CoupledTool tool(ball, {0.5, 5.0}, {0.5, 0.0});
    const contact::SurfacePoints nothing(16);
    for (int k = 0; k < 10; ++k) {
        const Eigen::Vector3d f = tool.update(at(10.0 - k), nothing, 1e-3);
        EXPECT_LT(f.norm(), 1e-12);
        EXPECT_LT((tool.proxy().position - Eigen::Vector3d(0, 0, 10.0 - k)).norm(), 1e-12);
    }
}

TEST(CoupledTool, AgainstAWallTheProxyStopsWhereSpringAndContactBalance)
{
    // A 10 x 10 mm flat punch (margin 0.5 mm) pushed 3 mm past the wall by the device: the proxy
    // stops where the spring kc (proxy - device) balances the contact, and the force felt is both.
    const contact::ToolShape punch = contact::ToolShape::box({10, 10, 4});
    const double kc = 0.5, k = 5.0;
    haptics::CoupledTool tool(punch, {0.5, k}, {kc, 0.0});
    const contact::SurfacePoints surface = wall();
    tool.update(at(2.0 + 0.5), surface, 1e-3); // the face touching the wall's margin
    Eigen::Vector3d f;
    for (int tick = 0; tick < 200; ++tick) f = tool.update(at(2.0 + 0.5 - 3.0), surface, 1e-3);
    const Eigen::Vector3d before = f;
    f = tool.update(at(2.0 + 0.5 - 3.0), surface, 1e-3);
    EXPECT_LT((f - before).norm(), 1e-9 * before.norm()); // settled, no chatter
    EXPECT_GT(f.z(), 0.0);                                // the wall pushes the hand back
    EXPECT_NEAR(f.x(), 0.0, 1e-9);
    EXPECT_NEAR(f.y(), 0.0, 1e-9);
    // The force felt is the spring's and equals the contact force on the proxy.
    EXPECT_NEAR(f.z(), kc * (tool.proxy().position.z() - (2.0 + 0.5 - 3.0)), 1e-9);
    EXPECT_NEAR(f.z(), tool.contact().force_on_tool_n.z(), 1e-6 * f.z());
    // The proxy stays above the device: it sank in only by the penalty depth.
    const double depth = 0.5 - (tool.proxy().position.z() - 2.0);
    EXPECT_GT(depth, 0.0);
    EXPECT_LT(depth, 0.5);
}

TEST(CoupledTool, AStiffContactStaysStable)
{
    // Contact 100 times stiffer than the coupling: the implicit proxy update neither overshoots
    // nor oscillates when the device jumps into the wall.
    const contact::ToolShape ball = contact::ToolShape::sphere(3.0);
    haptics::CoupledTool tool(ball, {0.5, 500.0}, {0.5, 0.0});
    const contact::SurfacePoints surface = wall();
    tool.update(at(5.0), surface, 1e-3);
    double previous = 0.0;
    for (int k = 0; k < 100; ++k) {
        const Eigen::Vector3d f = tool.update(at(-5.0), surface, 1e-3);
        ASSERT_TRUE(f.allFinite());
        EXPECT_LT(f.norm(), 0.5 * 10.0 + 1e-9); // never more than the spring stretched the whole way
        if (k > 2) {
            EXPECT_NEAR(f.norm(), previous, 1e-6 + 1e-3 * previous);
        }
        previous = f.norm();
    }
}
