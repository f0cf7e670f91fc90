// The convex hull holds every point and turns counter-clockwise.

#include "contact/convex_hull.hpp"

#include <gtest/gtest.h>

#include <random>

using namespace vox::contact;

TEST(ConvexHull, HoldsEveryPointCounterClockwise)
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
