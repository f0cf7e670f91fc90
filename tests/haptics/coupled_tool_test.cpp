// Virtual coupling: in free space the proxy is the device and nothing is felt; against a wall the
// proxy stops where the coupling spring and the contact balance, and the user feels that force,
// pointing out of the wall, steady from tick to tick however stiff the contact.

#include "haptics/coupled_tool.hpp"
#include "surface_snapshots.hpp"

#include <gtest/gtest.h>

#include <vector>

using namespace vox;

namespace {

contact::SurfacePoints wall() { return test::flat_wall(); }

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
    haptics::CoupledTool tool(ball, {0.5, 5.0}, {0.5, 0.0}, 41 * 41);
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
    haptics::CoupledTool tool(punch, {0.5, k}, {kc, 0.0}, 41 * 41);
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
    haptics::CoupledTool tool(ball, {0.5, 500.0}, {0.5, 0.0}, 41 * 41);
    const contact::SurfacePoints surface = wall();
    tool.update(at(5.0), surface, 1e-3);
    // The proxy stops where the ball first touches, then settles tick by tick; the force never
    // overshoots the spring's full stretch and its changes die out without changing sign twice.
    std::vector<double> force;
    for (int k = 0; k < 200; ++k) {
        const Eigen::Vector3d f = tool.update(at(-5.0), surface, 1e-3);
        ASSERT_TRUE(f.allFinite());
        EXPECT_LT(f.norm(), 0.5 * 10.0 + 1e-9);
        force.push_back(f.norm());
    }
    int reversals = 0;
    for (std::size_t k = 2; k < force.size(); ++k)
        reversals += (force[k] - force[k - 1]) * (force[k - 1] - force[k - 2]) < -1e-18;
    EXPECT_LE(reversals, 1);
    EXPECT_NEAR(force.back(), force[force.size() - 2], 1e-6 * force.back());
}

TEST(CoupledTool, AFastThinToolDoesNotTunnelThroughTheSurface)
{
    // A 0.5 mm blade, edge down, over the wall; the device jumps from 3 mm above to 5 mm below the
    // wall in one tick. The blade touches no point at either pose (it would be past them), so a
    // discrete test sees nothing; the proxy must stop at the wall, and a contact stiff enough to
    // carry the spring's pull (a row of 11 points under the edge) keeps it there.
    const contact::ToolShape blade = contact::ToolShape::box({10, 0.5, 0.5});
    haptics::CoupledTool tool(blade, {0.25, 500.0}, {0.5, 0.0}, 41 * 41);
    const contact::SurfacePoints surface = wall();
    tool.update(at(3.0), surface, 1e-3);
    tool.update(at(-5.0), surface, 1e-3);
    // Stopped where its pushing shape (0.25 + 0.25 mm below the centre) reached its depth bound
    // into the wall (contact/proxy.hpp: 90 % of the pushing shape's half-thickness, 0.45 mm).
    const double bound = contact::depth_bound_mm(blade, 0.25);
    EXPECT_NEAR(bound, 0.45, 1e-12);
    EXPECT_NEAR(tool.proxy().position.z(), 0.5 - bound, 2e-3);
    // And held there on the following ticks, pushing the hand back up.
    Eigen::Vector3d f;
    for (int tick = 0; tick < 50; ++tick) f = tool.update(at(-5.0), surface, 1e-3);
    EXPECT_GT(tool.proxy().position.z(), 0.5 - bound - 1e-3); // the blade's middle stays above the wall
    EXPECT_GT(f.z(), 2.0);                                    // the hand, 5 mm below, is pushed back up
}

TEST(CoupledTool, ANeedleIsHeldAtAFaceBetweenDistantPoints)
{
    // Two triangles 20 mm across, sampled only at their corners: a 0.2 mm needle jerked through
    // the middle touches no point, ever. The mesh sweep stops it at the face; the hand, 2 mm
    // below, feels the coupling spring (0.5 N/mm x 2.2 mm) pushing it back up.
    const contact::SurfacePoints square = test::coarse_square();
    const contact::ToolShape needle = contact::ToolShape::sphere(0.2);
    haptics::CoupledTool tool(needle, {0.1, 5.0}, {0.5, 0.0}, square.capacity());
    Eigen::Vector3d f;
    tool.update(at(2.0), square, 1e-3);
    for (int tick = 0; tick < 40; ++tick) f = tool.update(at(-2.0), square, 1e-3); // a jump, then held down
    EXPECT_GT(tool.proxy().position.z(), 0.19); // the needle's mesh is above the face
    EXPECT_LT(tool.proxy().position.z(), 0.25);
    EXPECT_NEAR(f.z(), 0.5 * (tool.proxy().position.z() + 2.0), 1e-9);
    EXPECT_GT(f.z(), 1.0);
}

TEST(CoupledTool, AContactPreparedAfterTheTickGivesTheForcesOfOneMeasuredInIt)
{
    // The loop measures the contact at the proxy after sending the force (prepare), for the next
    // tick: the same blade driven through a press, a slide and a jab (swept against the mesh)
    // feels the same forces, bit for bit, as one that measures in every tick; where the next
    // tick comes with another snapshot, the prepared contact is not used.
    const contact::SurfacePoints wall = test::flat_wall(41, true), lower = [] {
        contact::SurfacePoints s = test::flat_wall(41, true);
        for (std::size_t i = 0; i < s.count; ++i) s.positions_mm[i].z() -= 0.3;
        s.t_s = 1.0;
        s.index();
        return s;
    }();
    const contact::ToolShape blade = contact::ToolShape::box({10, 0.5, 4});
    haptics::CoupledTool measured(blade, {0.25, 5.0}, {}, wall.capacity()), prepared(blade, {0.25, 5.0}, {}, wall.capacity());
    auto device = [](int k) {
        haptics::DeviceState d;
        const double t = 1e-3 * k;
        d.position_mm = t < 0.2 ? Eigen::Vector3d(0, 0, 5 - 20 * t) : t < 0.3 ? Eigen::Vector3d(20 * (t - 0.2), 0, 1) : Eigen::Vector3d(2, 0, k < 301 ? 5 : -2);
        return d;
    };
    int swept = 0;
    for (int k = 0; k < 400; ++k) {
        const contact::SurfacePoints& surface = k < 250 ? wall : lower; // a new snapshot at tick 250
        const Eigen::Vector3d a = measured.update(device(k), surface, 1e-3), b = prepared.update(device(k), surface, 1e-3);
        ASSERT_EQ(a, b) << "tick " << k;
        ASSERT_EQ(measured.proxy().position, prepared.proxy().position) << "tick " << k;
        swept += prepared.sweep().swept_mesh();
        EXPECT_EQ(prepared.used_prepared(), k != 0 && k != 250) << "tick " << k;
        // Prepared on the snapshot the next tick uses, except before the new one arrives.
        prepared.prepare(device(k), k == 249 ? wall : (k + 1 < 250 ? wall : lower), 1e-3);
    }
    EXPECT_GT(swept, 0);
    EXPECT_GT(prepared.contact().force_on_tool_n.norm(), 0.05); // in contact at the end
}

TEST(CoupledTool, APreparedProxyTakesTheDeviceOrientationOfTheTickBefore)
{
    const contact::ToolShape blade = contact::ToolShape::box({10, 0.5, 4});
    haptics::CoupledTool tool(blade, {0.25, 5.0}, {}, 16);
    const contact::SurfacePoints nothing(16);
    haptics::DeviceState d;
    d.position_mm = Eigen::Vector3d(0, 0, 5);
    tool.update(d, nothing, 1e-3); // unprepared: the device's own orientation
    EXPECT_TRUE(tool.proxy().orientation.isApprox(d.orientation));
    for (int k = 1; k <= 3; ++k) {
        const Eigen::Quaterniond before = d.orientation;
        tool.prepare(d, nothing, 1e-3);
        d.orientation = Eigen::Quaterniond(Eigen::AngleAxisd(0.1 * k, Eigen::Vector3d::UnitX()));
        tool.update(d, nothing, 1e-3);
        EXPECT_TRUE(tool.proxy().orientation.isApprox(before)) << k;
    }
}

TEST(CoupledTool, AProbePulledFarPastAWallIsHeldAtItsDepthBoundAndPassesOnlyWhileCutting)
{
    // A 2 mm ball pulled 20 mm into the wall through a stiff spring (10 N at every millimetre,
    // far beyond any device's maximum): it stays at the wall, no point deeper than the bound.
    const contact::ToolShape ball = contact::ToolShape::sphere(2.0);
    haptics::CoupledTool tool(ball, {0.5, 5.0}, {10.0, 0.0}, 41 * 41);
    contact::SurfacePoints surface = wall();
    surface.index();
    tool.update(at(4.0), surface, 1e-3);
    Eigen::Vector3d f;
    for (int tick = 0; tick < 300; ++tick) f = tool.update(at(-20.0), surface, 1e-3);
    const double bound = contact::depth_bound_mm(ball, 0.5);
    EXPECT_LE(contact::deepest_point_mm(tool.proxy(), 0.5, surface), bound + 1e-3);
    EXPECT_GT(tool.proxy().position.z(), 0.0);
    EXPECT_NEAR(f.z(), 10.0 * (tool.proxy().position.z() + 20.0), 1e-6 * f.z()); // the whole pull, felt
    // In a cut episode the material gives way: the proxy goes where the device is.
    tool.set_passing(true);
    tool.update(at(-20.0), surface, 1e-3);
    EXPECT_NEAR(tool.proxy().position.z(), -20.0, 1e-12);
}
