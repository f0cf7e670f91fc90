// The region a blade's profile covers moving and turning within its plane: a translation covers
// exactly the profile's Minkowski sum with the segment; a turn covers the turned profile; frames
// add up; the convex hull holds every point and turns counter-clockwise.

#include "contact/swept_profile.hpp"

#include <Eigen/Geometry>
#include <gtest/gtest.h>

#include <cmath>
#include <random>

using namespace vox::contact;

namespace {

std::vector<Eigen::Vector2d> box(double half_x, double half_y)
{
    return {{-half_x, -half_y}, {half_x, -half_y}, {half_x, half_y}, {-half_x, half_y}};
}

Eigen::Matrix2d turn(double radians)
{
    return Eigen::Rotation2Dd(radians).toRotationMatrix();
}

} // namespace

TEST(SweptProfile, ATranslationCoversTheProfileSweptAlongItsSegment)
{
    SweptProfile swept(box(1.0, 1.0));
    EXPECT_FALSE(swept.covers({0.0, 0.0}));
    swept.add(Eigen::Matrix2d::Identity(), {0.0, 0.0}, Eigen::Matrix2d::Identity(), {4.0, 2.0});
    // The Minkowski sum of the square and the segment (0,0)-(4,2): a hexagon.
    EXPECT_TRUE(swept.covers({0.0, 0.0}));
    EXPECT_TRUE(swept.covers({2.0, 1.0}));
    EXPECT_TRUE(swept.covers({4.9, 2.9}));
    EXPECT_TRUE(swept.covers({-0.9, 0.9}));
    EXPECT_FALSE(swept.covers({-0.9, 1.6})); // above the upper-left corner's path: y <= 1 + (x + 1) / 2
    EXPECT_FALSE(swept.covers({4.9, 0.3}));  // below the lower-right corner's path: y >= -1 + (x - 1) / 2
    EXPECT_FALSE(swept.covers({5.1, 2.0}));
    swept.clear();
    EXPECT_TRUE(swept.empty());
    EXPECT_FALSE(swept.covers({0.0, 0.0}));
}

TEST(SweptProfile, ABladeTurningWithinItsPlaneCoversWhereItTurnedTo)
{
    // A blade 10 long and 0.2 thick turning 60 degrees about its centre over one frame.
    SweptProfile swept(box(5.0, 0.1));
    swept.add(turn(0.0), {0.0, 0.0}, turn(M_PI / 3.0), {0.0, 0.0});
    const Eigen::Vector2d along_end = 4.0 * Eigen::Vector2d(std::cos(M_PI / 3.0), std::sin(M_PI / 3.0));
    EXPECT_TRUE(swept.covers(along_end)); // on the blade where it ended
    EXPECT_TRUE(swept.covers({4.0, 0.0})); // where it started
    EXPECT_TRUE(swept.covers(2.0 * Eigen::Vector2d(std::cos(M_PI / 6.0), std::sin(M_PI / 6.0)))); // swept between
    EXPECT_FALSE(swept.covers(4.0 * Eigen::Vector2d(std::cos(2.0 * M_PI / 3.0), std::sin(2.0 * M_PI / 3.0)))); // never there
    // Kept in its first orientation (what the stroke did before) it would miss the end.
    SweptProfile fixed(box(5.0, 0.1));
    fixed.add(turn(0.0), {0.0, 0.0}, turn(0.0), {0.0, 0.0});
    EXPECT_FALSE(fixed.covers(along_end));
    // Frames add up: a second frame moving the turned blade.
    swept.add(turn(M_PI / 3.0), {0.0, 0.0}, turn(M_PI / 3.0), {0.0, 10.0});
    EXPECT_TRUE(swept.covers(along_end + Eigen::Vector2d(0.0, 9.0)));
    EXPECT_TRUE(swept.covers({4.0, 0.0}));
}

TEST(SweptProfile, TheConvexHullHoldsEveryPointCounterClockwise)
{
    std::mt19937 random(3);
    std::uniform_real_distribution<double> coordinate(-1.0, 1.0);
    std::vector<Eigen::Vector2d> points;
    for (int i = 0; i < 200; ++i) points.emplace_back(coordinate(random), coordinate(random));
    const std::vector<Eigen::Vector2d> hull = convex_hull(points);
    ASSERT_GE(hull.size(), 3u);
    for (std::size_t k = 0; k < hull.size(); ++k) {
        const Eigen::Vector2d& a = hull[k];
        const Eigen::Vector2d& b = hull[(k + 1) % hull.size()];
        for (const Eigen::Vector2d& p : points) {
            const double side = (b.x() - a.x()) * (p.y() - a.y()) - (b.y() - a.y()) * (p.x() - a.x());
            EXPECT_GE(side, -1e-12); // every point left of (or on) every edge
        }
    }
}
