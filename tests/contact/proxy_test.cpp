// The proxy held outside what it does not cut: however far past a thin plate the driver goes and
// however stiff the spring, no surface point gets deeper into the pushing shape than the bound,
// the proxy stays on the plate's near side, and the load scale makes the contact carry the pull;
// along a wall the proxy slides to where the driver is; a jab across widely spaced points is
// stopped by the mesh check.

#include "contact/proxy.hpp"
#include "surface_snapshots.hpp"

#include <gtest/gtest.h>

using namespace vox;

namespace {

/// A plate 2 mm thick: its top z = 0 (normal +z) and its bottom z = -2 (normal -z), each sampled
/// on a 1 mm grid of n x n points, 1 mm^2 each; no triangles.
contact::SurfacePoints thin_plate(int n = 31)
{
    contact::SurfacePoints s(static_cast<std::size_t>(2 * n * n));
    const double half = 0.5 * (n - 1);
    for (int side = 0; side < 2; ++side)
        for (int i = 0; i < n; ++i)
            for (int j = 0; j < n; ++j) {
                s.positions_mm[s.count] = Eigen::Vector3d(i - half, j - half, side == 0 ? 0.0 : -2.0);
                s.normals[s.count] = side == 0 ? Eigen::Vector3d::UnitZ() : Eigen::Vector3d(-Eigen::Vector3d::UnitZ());
                s.areas_mm2[s.count++] = 1.0;
            }
    s.index();
    return s;
}

} // namespace

TEST(Proxy, DepthBoundIsHalfAMillimetreOrTheMarginAndNeverPastTheMiddle)
{
    EXPECT_NEAR(contact::depth_bound_mm(contact::ToolShape::sphere(2.0), 0.2), 0.5, 1e-12);
    EXPECT_NEAR(contact::depth_bound_mm(contact::ToolShape::sphere(2.0), 1.0), 1.02, 1e-12);
    // A 0.1 mm blade with a 0.1 mm margin: its pushing shape is 0.3 mm thick.
    EXPECT_NEAR(contact::depth_bound_mm(contact::ToolShape::box({20, 0.1, 10}), 0.1), 0.9 * 0.15, 1e-12);
}

TEST(Proxy, AProbeDrivenFarPastAThinPlateStaysOnIt)
{
    // A 4 mm probe (ball of radius 2, margin 0.5) on a plate thinner than itself, driven from 1 to
    // 15 mm below the plate's top through springs from a device's 0.5 N/mm to 1000 N/mm (forces
    // far beyond any device's maximum).
    const contact::ToolShape probe = contact::ToolShape::sphere(2.0);
    const contact::ContactParameters parameters{0.5, 5.0};
    const contact::SurfacePoints plate = thin_plate();
    for (const double kc : {0.5, 10.0, 100.0, 1000.0})
        for (const double below : {1.0, 5.0, 15.0}) {
            contact::ProxyMover mover(probe, parameters, plate.capacity());
            contact::PlacedShape proxy{&probe, Eigen::Vector3d(0.3, -0.2, 6.0)};
            const Eigen::Vector3d driver(0.3, -0.2, -below);
            const contact::ContactTotals c = mover.settle(proxy, driver, kc, plate);
            const double deepest = contact::deepest_point_mm(proxy, parameters.margin_mm, plate);
            EXPECT_LE(deepest, mover.bound_mm() + 1e-3) << "kc " << kc << ", driver " << below << " mm below";
            // Between the plate's points (1 mm apart) the ball's centre stays at least the bound's
            // distance from each, 2.5 - bound, of which at most 0.5 mm^2 across.
            const double rho = 2.5 - mover.bound_mm();
            EXPECT_GT(proxy.position.z(), std::sqrt(rho * rho - 0.5) - 1e-3) << "the probe stays on the plate's top";
            // The contact, scaled, carries the spring's pull.
            const Eigen::Vector3d pull = kc * (driver - proxy.position);
            const double scale = contact::load_scale(pull, c.force_on_tool_n, deepest, mover.bound_mm());
            EXPECT_GE(scale, 1.0);
            if (scale > 1.0 + 1e-9) {
                EXPECT_NEAR(scale * c.force_on_tool_n.z(), -pull.z(), 1e-6 * std::abs(pull.z()));
            }
        }
}

TEST(Proxy, ASoftPushSitsWhereSpringAndContactBalance)
{
    // A weak spring: the proxy does not reach the bound and the contact carries the pull unscaled.
    const contact::ToolShape probe = contact::ToolShape::sphere(2.0);
    const contact::SurfacePoints plate = thin_plate();
    contact::ProxyMover mover(probe, {0.5, 50.0}, plate.capacity());
    contact::PlacedShape proxy{&probe, Eigen::Vector3d(0, 0, 5.0)};
    const Eigen::Vector3d driver(0, 0, 2.0);
    const contact::ContactTotals c = mover.settle(proxy, driver, 0.1, plate);
    const Eigen::Vector3d pull = 0.1 * (driver - proxy.position);
    EXPECT_NEAR(c.force_on_tool_n.z(), -pull.z(), 1e-6);
    EXPECT_LT(contact::deepest_point_mm(proxy, 0.5, plate), mover.bound_mm());
    EXPECT_NEAR(contact::load_scale(pull, c.force_on_tool_n, 0.0, mover.bound_mm()), 1.0, 1e-6);
}

TEST(Proxy, TheProxySlidesAlongAWallToNearAboveItsDriver)
{
    const contact::ToolShape probe = contact::ToolShape::sphere(2.0);
    const contact::SurfacePoints wall = test::flat_wall(41);
    contact::SurfacePoints indexed = wall;
    indexed.index();
    contact::ProxyMover mover(probe, {0.5, 5.0}, indexed.capacity());
    contact::PlacedShape proxy{&probe, Eigen::Vector3d(-6, 0, 2.4)};
    const Eigen::Vector3d driver(6, 3, -4); // below the wall and 12 mm along it
    mover.settle(proxy, driver, 100.0, indexed, 200);
    // Frictionless, but the wall is points 1 mm apart: the ball rests in the hollow between them
    // nearest its driver.
    EXPECT_NEAR(proxy.position.x(), driver.x(), 1.0);
    EXPECT_NEAR(proxy.position.y(), driver.y(), 1.0);
    EXPECT_LE(contact::deepest_point_mm(proxy, 0.5, indexed), mover.bound_mm() + 1e-3);
}

TEST(Proxy, AJabAcrossWidelySpacedPointsStopsAtTheFace)
{
    // Points 20 mm apart: a 1 mm ball jabbed through the square between them meets no point; the
    // tool's mesh against the triangles stops it at the face.
    const contact::ToolShape ball = contact::ToolShape::sphere(1.0);
    contact::SurfacePoints square = test::coarse_square();
    contact::ProxyMover mover(ball, {0.2, 5.0}, square.capacity());
    contact::PlacedShape proxy{&ball, Eigen::Vector3d(1, 2, 5)};
    const Eigen::Vector3d moved = mover.move(proxy, Eigen::Vector3d(0, 0, -15), square);
    EXPECT_TRUE(mover.blocked());
    EXPECT_GT(proxy.position.z(), 0.0);
    EXPECT_LT(moved.norm(), 5.0);
}

TEST(Proxy, MaterialPushedInPastTheBoundScalesTheContactUp)
{
    EXPECT_NEAR(contact::load_scale(Eigen::Vector3d::Zero(), Eigen::Vector3d(0, 0, 1), 2.0, 0.5), 4.0, 1e-12);
    EXPECT_NEAR(contact::load_scale(Eigen::Vector3d::Zero(), Eigen::Vector3d(0, 0, 1), 0.2, 0.5), 1.0, 1e-12);
    // A pull away from the contact does not scale it.
    EXPECT_NEAR(contact::load_scale(Eigen::Vector3d(0, 0, 3), Eigen::Vector3d(0, 0, 1), 0.2, 0.5), 1.0, 1e-12);
}
