// Obstacles: their signed distances against closed forms (a plane's, a box's) and against each
// other (a closed mesh shaped as a box), the broad phase never missing a box that reaches in, and
// the contact: the normal penalty k d a / 1 cm^2 along the obstacle's normal, friction that
// sticks below mu |f_n| with the spring's own stiffness and slips at exactly mu |f_n|, anchors
// kept from call to call and let go when the point leaves.

#include "contact/obstacle.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <vector>

using namespace vox::contact;
using Eigen::Vector3d;

namespace {

/// Exact signed distance to the box [lo, hi].
double box_distance(const Vector3d& p, const Vector3d& lo, const Vector3d& hi)
{
    const Vector3d c = 0.5 * (lo + hi), h = 0.5 * (hi - lo);
    const Vector3d q = (p - c).cwiseAbs() - h;
    return q.cwiseMax(0.0).norm() + std::min(q.maxCoeff(), 0.0);
}

TEST(Obstacle, PlaneAndBoxDistancesAreTheClosedForms)
{
    const Vector3d n = Vector3d(1, -2, 3).normalized(), point(4, 5, -6);
    const Obstacle plane = Obstacle::plane(point, n);
    const Vector3d lo(-10, -5, -20), hi(30, 15, -1);
    const Obstacle box = Obstacle::box(lo, hi);
    std::mt19937 rng(7);
    std::uniform_real_distribution<double> u(-40.0, 40.0);
    for (int i = 0; i < 500; ++i) {
        const Vector3d p(u(rng), u(rng), u(rng));
        Vector3d g;
        EXPECT_NEAR(plane.signed_distance(p, &g), (p - point).dot(n), 1e-12);
        EXPECT_NEAR((g - n).norm(), 0.0, 1e-15);
        EXPECT_NEAR(box.signed_distance(p, &g), box_distance(p, lo, hi), 1e-9);
        // The gradient points the way the distance grows.
        const double d = box.signed_distance(p);
        EXPECT_GT(box.signed_distance(p + 1e-4 * g), d);
    }
}

TEST(Obstacle, ClosedMeshShapedAsABoxMeasuresAsTheBox)
{
    const Vector3d lo(-10, -5, -20), hi(30, 15, -1);
    const Obstacle box = Obstacle::box(lo, hi);
    TriangleMesh m = ToolShape::box(hi - lo).mesh();
    for (Vector3d& p : m.positions) p += 0.5 * (lo + hi);
    const Obstacle mesh = Obstacle::mesh(m);
    std::mt19937 rng(8);
    std::uniform_real_distribution<double> u(-40.0, 40.0);
    for (int i = 0; i < 300; ++i) {
        const Vector3d p(u(rng), u(rng), u(rng));
        const double d = box.signed_distance(p);
        // Outside the distance to the box's faces, edges and corners; inside, to its nearest face.
        EXPECT_NEAR(mesh.signed_distance(p), d, 1e-9) << p.transpose();
    }
}

TEST(Obstacle, BroadPhaseNeverMissesABoxReachingIn)
{
    const std::vector<Obstacle> obstacles{Obstacle::plane({0, 0, 0}, Vector3d(0.3, -0.4, 0.8).normalized()),
                                          Obstacle::box({-5, -5, -5}, {5, 5, 5})};
    std::mt19937 rng(9);
    std::uniform_real_distribution<double> u(-20.0, 20.0), s(0.1, 6.0);
    for (const Obstacle& o : obstacles)
        for (int i = 0; i < 400; ++i) {
            const Vector3d c(u(rng), u(rng), u(rng)), h(s(rng), s(rng), s(rng));
            const Eigen::AlignedBox3d b(c - h, c + h);
            bool inside = false; // sampled on a 5 x 5 x 5 lattice, corners included
            for (int x = 0; x < 5; ++x)
                for (int y = 0; y < 5; ++y)
                    for (int z = 0; z < 5; ++z)
                        inside |= o.signed_distance(b.min() + (b.max() - b.min()).cwiseProduct(Vector3d(x, y, z) / 4.0)) < 0.0;
            if (inside) {
                EXPECT_TRUE(o.may_reach(b));
            }
        }
}

TEST(Obstacle, NormalForceIsThePenaltyAlongTheObstaclesNormal)
{
    const Obstacle table = [] {
        Obstacle o = Obstacle::plane({0, 0, 0}, {0, 0, 1});
        o.stiffness_n_per_mm = 20.0;
        return o;
    }();
    const std::vector<Vector3d> points{{0, 0, -0.5}, {1, 0, 0.2}, {2, 0, -0.1}};
    const std::vector<double> areas{4.0, 4.0, 2.0};
    const std::vector<Vector3d> still(3, Vector3d::Zero());
    const std::vector<std::uint64_t> keys{1, 2, 3};
    FrictionAnchors anchors;
    const ContactResult c = obstacle_contact(table, points, areas, still, 0.01, keys, anchors);
    ASSERT_EQ(c.points.size(), 2u); // the point above the table is free
    EXPECT_NEAR(c.points[0].force_n.z(), 20.0 / 100.0 * 4.0 * 0.5, 1e-12);
    EXPECT_NEAR(c.points[1].force_n.z(), 20.0 / 100.0 * 2.0 * 0.1, 1e-12);
    EXPECT_NEAR(c.points[0].stiffness_n_per_mm, 20.0 / 100.0 * 4.0, 1e-12);
    EXPECT_NEAR((c.force_on_tool_n + c.points[0].force_n + c.points[1].force_n).norm(), 0.0, 1e-15);
    EXPECT_EQ(anchors.size(), 2u);
    EXPECT_EQ(anchors.count(2), 0u);
}

TEST(Obstacle, FrictionSticksBelowTheLimitAndSlipsAtIt)
{
    Obstacle table = Obstacle::plane({0, 0, 0}, {0, 0, 1});
    table.friction = 0.5;
    const std::vector<double> area{100.0}; // 1 cm^2: k = 10 N/mm
    const std::vector<std::uint64_t> key{42};
    const std::vector<Vector3d> still{Vector3d::Zero()};
    FrictionAnchors anchors;
    // Touches at x = 0, 0.01 mm deep: |f_n| = 0.1 N, the limit 0.05 N; the anchor is where it
    // touched, the spring reaches the limit over k_stick_give_mm.
    ContactResult c = obstacle_contact(table, std::vector<Vector3d>{{0, 0, -0.01}}, area, still, 0.01, key, anchors);
    EXPECT_NEAR((c.points[0].force_n - Vector3d(0, 0, 0.1)).norm(), 0.0, 1e-12);
    const double spring = 0.05 / k_stick_give_mm;
    ASSERT_LT(spring, 10.0); // no stiffer than the normal penalty
    // Moved 0.004 mm along x: pulled back by the spring; it sticks.
    c = obstacle_contact(table, std::vector<Vector3d>{{0.004, 0, -0.01}}, area, still, 0.01, key, anchors);
    EXPECT_NEAR(c.points[0].force_n.x(), -spring * 0.004, 1e-12);
    EXPECT_NEAR(c.points[0].friction_stiffness_n_per_mm(0, 0), spring, 1e-9);
    EXPECT_NEAR(c.points[0].friction_stiffness_n_per_mm(2, 2), 0.0, 1e-12); // not along the normal
    EXPECT_NEAR((anchors.at(42) - Vector3d(0, 0, -0.01)).norm(), 0.0, 1e-15);
    // Moved 3 mm: it slips, pulled back by exactly mu |f_n| against its motion, and the anchor
    // follows at the spring's reach; nothing resists it along the slip.
    c = obstacle_contact(table, std::vector<Vector3d>{{3, 0, -0.01}}, area, still, 0.01, key, anchors);
    EXPECT_NEAR((c.points[0].force_n - Vector3d(-0.05, 0, 0.1)).norm(), 0.0, 1e-12);
    EXPECT_NEAR(c.points[0].friction_stiffness_n_per_mm(0, 0), 0.0, 1e-9);
    EXPECT_NEAR(c.points[0].friction_stiffness_n_per_mm(1, 1), spring, 1e-9);
    EXPECT_NEAR((anchors.at(42) - Vector3d(3 - k_stick_give_mm, 0, -0.01)).norm(), 0.0, 1e-12);
    // Sliding at 1 m/s, a step of 10 ms slides 10 mm: the spring is softened to reach the limit
    // over that, not over k_stick_give_mm.
    const std::vector<Vector3d> sliding{Vector3d(1000, 0, 0)};
    anchors.clear();
    static_cast<void>(obstacle_contact(table, std::vector<Vector3d>{{0, 0, -0.01}}, area, sliding, 0.01, key, anchors));
    c = obstacle_contact(table, std::vector<Vector3d>{{1, 0, -0.01}}, area, sliding, 0.01, key, anchors);
    EXPECT_NEAR(c.points[0].force_n.x(), -0.05 / 10.0 * 1.0, 1e-12);
    // Lifted off: the anchor is let go.
    c = obstacle_contact(table, std::vector<Vector3d>{{1, 0, 0.01}}, area, still, 0.01, key, anchors);
    EXPECT_TRUE(c.points.empty());
    EXPECT_TRUE(anchors.empty());
}

} // namespace
