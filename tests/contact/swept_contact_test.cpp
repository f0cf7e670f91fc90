// Continuous collision for the haptic proxy: a thin blade that passes a point between two poses
// is caught at the moment it touches, to the tolerance; a point the tool touches at either pose,
// or never comes near, is not a missed contact.

#include "contact/swept_contact.hpp"

#include <gtest/gtest.h>

using namespace vox::contact;
using Eigen::Vector3d;

namespace {

SurfacePoints one_point(const Vector3d& p)
{
    SurfacePoints s(1);
    s.positions_mm[0] = p;
    s.normals[0] = Vector3d::UnitZ();
    s.areas_mm2[0] = 1.0;
    s.count = 1;
    return s;
}

const ToolShape blade = ToolShape::box({10, 0.5, 10}); // 0.5 mm thick along y

PlacedShape at(const Vector3d& p, const Eigen::Quaterniond& q = Eigen::Quaterniond::Identity()) { return {&blade, p, q}; }

} // namespace

TEST(SweptContact, AThinBladeSweepingPastAPointIsCaughtWhenItTouches)
{
    // The blade moves 10 mm along y in one step, from y = -5 to 5, past a point at y = 3. Its
    // pushing shape (0.25 + 0.5 = 0.75 mm half-thickness) first touches the point when the
    // blade's centre reaches y = 3 - 0.75, at t = (3 - 0.75 - (-5)) / 10, and it is caught 1 um
    // further in (so that the penalty contact has it).
    const SurfacePoints s = one_point({0, 3, 0});
    const double t = first_missed_contact(at({0, -5, 0}), at({0, 5, 0}), 0.5, s);
    EXPECT_NEAR(t, (3.0 - 0.75 + 0.001 + 5.0) / 10.0, 2e-5);
}

TEST(SweptContact, ContactsSeenAtATickAreNotMissed)
{
    const SurfacePoints s = one_point({0, 0, 0});
    EXPECT_EQ(first_missed_contact(at({0, -5, 0}), at({0, 0.2, 0}), 0.5, s), 1.0); // inside at the end
    EXPECT_EQ(first_missed_contact(at({0, 0.1, 0}), at({0, 5, 0}), 0.5, s), 1.0);  // inside at the start
    EXPECT_EQ(first_missed_contact(at({20, -5, 0}), at({20, 5, 0}), 0.5, s), 1.0); // never near
    EXPECT_EQ(first_missed_contact(at({0, -5, 0}), at({0, -5, 0}), 0.5, s), 1.0);  // not moving
}

TEST(SweptContact, ATurningBladeIsCaughtToo)
{
    // The blade lies in the x-z plane and turns 90 degrees about z in one step; its mid-plane
    // sweeps past a point 3 mm from the axis at 45 degrees, which is outside it at both ends.
    const SurfacePoints s = one_point(Vector3d(3, 3, 0) / std::sqrt(2.0));
    const Eigen::Quaterniond quarter(Eigen::AngleAxisd(M_PI / 2, Vector3d::UnitZ()));
    const double t = first_missed_contact(at({0, 0, 0}), at({0, 0, 0}, quarter), 0.5, s);
    // The pushing shape's half-thickness 0.75 mm at 3 mm from the axis: touched 14.3 degrees
    // before the blade's mid-plane reaches the point's 45 degrees.
    const double expected = (M_PI / 4 - std::asin(0.75 / 3.0)) / (M_PI / 2);
    EXPECT_NEAR(t, expected, 1e-3);
}
