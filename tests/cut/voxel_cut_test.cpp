// The separating cut's geometry: which segments a triangle of the cutting surface crosses, the
// tie rule for centres exactly on the surface (through degenerate positions -1e-12, 0, 1e-12),
// and the surface a blade sweeps over a stroke.

#include "cut/voxel_cut.hpp"

#include <Eigen/Geometry>
#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <random>
#include <utility>
#include <vector>

using namespace vox;
using namespace vox::cut;
using contact::PlacedShape;
using contact::ToolShape;
using Eigen::Vector3d;
using Triangle = std::array<Vector3d, 3>;
using XZ = std::pair<double, double>;

namespace {

const Triangle unit_triangle{Vector3d(0, 0, 0), Vector3d(1, 0, 0), Vector3d(0, 1, 0)};
const Vector3d up(0, 0, 1);

/// Whether the segment p-q crosses any triangle of the swept surface.
bool crosses(const SweptSurface& s, const Vector3d& p, const Vector3d& q)
{
    for (const Triangle& t : s.triangles)
        if (segment_crosses(p, q, t, s.normal)) return true;
    return false;
}

/// The pair of voxel centres either side of `centre` along `axis` (spacing `h`): which of the
/// pairs (centre - h e, centre) and (centre, centre + h e) the surface cuts.
std::pair<bool, bool> pairs_cut(const SweptSurface& s, const Vector3d& centre, const Vector3d& axis, double h = 1.0)
{
    return {crosses(s, centre - h * axis, centre), crosses(s, centre, centre + h * axis)};
}

PlacedShape at(const ToolShape& shape, const Vector3d& position,
               const Eigen::Quaterniond& orientation = Eigen::Quaterniond::Identity())
{
    return PlacedShape{&shape, position, orientation};
}

/// A segment across the blade plane y = y0 of the unturned tool, through (x, z).
std::pair<Vector3d, Vector3d> across(double x, double z, double y0 = 0.0)
{
    return {Vector3d(x, y0 - 0.5, z), Vector3d(x, y0 + 0.5, z)};
}

} // namespace

TEST(SegmentCrosses, ThroughTheInteriorEdgesAndCorners)
{
    EXPECT_TRUE(segment_crosses({0.2, 0.2, -1}, {0.2, 0.2, 1}, unit_triangle, up));
    EXPECT_TRUE(segment_crosses({0.2, 0.2, 1}, {0.2, 0.2, -1}, unit_triangle, up)); // either direction
    EXPECT_TRUE(segment_crosses({0.2, 0.2, 1}, {0.2, 0.2, -1}, unit_triangle, -up)); // either orientation
    // A slanted segment whose crossing point (0.25, 0.25) is inside.
    EXPECT_TRUE(segment_crosses({0.0, 0.5, -1}, {0.5, 0.0, 1}, unit_triangle, up));
    // Edges and corners belong to the triangle.
    EXPECT_TRUE(segment_crosses({0.5, 0.5, -1}, {0.5, 0.5, 1}, unit_triangle, up));
    EXPECT_TRUE(segment_crosses({0.5, 0.0, -1}, {0.5, 0.0, 1}, unit_triangle, up));
    EXPECT_TRUE(segment_crosses({0.0, 0.0, -1}, {0.0, 0.0, 1}, unit_triangle, up));
    EXPECT_TRUE(segment_crosses({1.0, 0.0, -1}, {1.0, 0.0, 1}, unit_triangle, up));
}

TEST(SegmentCrosses, MissesOutsideAnEdgeShortOfThePlaneAndParallel)
{
    EXPECT_FALSE(segment_crosses({0.6, 0.6, -1}, {0.6, 0.6, 1}, unit_triangle, up));   // beyond the hypotenuse
    EXPECT_FALSE(segment_crosses({-0.1, 0.3, -1}, {-0.1, 0.3, 1}, unit_triangle, up)); // beyond x = 0
    EXPECT_FALSE(segment_crosses({0.3, -0.1, -1}, {0.3, -0.1, 1}, unit_triangle, up)); // beyond y = 0
    // Just outside the hypotenuse and a corner, by far more than the edge tolerance.
    EXPECT_FALSE(segment_crosses({0.5 + 1e-9, 0.5, -1}, {0.5 + 1e-9, 0.5, 1}, unit_triangle, up));
    EXPECT_FALSE(segment_crosses({-1e-9, -1e-9, -1}, {-1e-9, -1e-9, 1}, unit_triangle, up));
    // Through the plane inside the triangle's projection but not reaching it.
    EXPECT_FALSE(segment_crosses({0.2, 0.2, 1}, {0.2, 0.2, 0.5}, unit_triangle, up));
    EXPECT_FALSE(segment_crosses({0.2, 0.2, -1}, {0.2, 0.2, -1e-6}, unit_triangle, up));
    // Parallel: above, and lying in the plane itself.
    EXPECT_FALSE(segment_crosses({0.1, 0.1, 0.5}, {0.3, 0.2, 0.5}, unit_triangle, up));
    EXPECT_FALSE(segment_crosses({0.1, 0.1, 0.0}, {0.3, 0.2, 0.0}, unit_triangle, up));
    // A degenerate triangle (an edge sliding along itself) crosses nothing.
    const Triangle flat{Vector3d(0, 0, 0), Vector3d(1, 0, 0), Vector3d(2, 0, 0)};
    EXPECT_FALSE(segment_crosses({0.5, -1, 0}, {0.5, 1, 0}, flat, up));
}

TEST(SegmentCrosses, AnEndpointOnThePlaneCountsOnTheSideTheNormalPointsTo)
{
    // p on the plane counts as the + side: crossed only when q lies on the - side.
    EXPECT_TRUE(segment_crosses({0.2, 0.2, 0}, {0.2, 0.2, -1}, unit_triangle, up));
    EXPECT_FALSE(segment_crosses({0.2, 0.2, 0}, {0.2, 0.2, 1}, unit_triangle, up));
    EXPECT_FALSE(segment_crosses({0.2, 0.2, 0}, {0.2, 0.2, -1}, unit_triangle, -up));
    EXPECT_TRUE(segment_crosses({0.2, 0.2, 0}, {0.2, 0.2, 1}, unit_triangle, -up));
    // The triangle's winding does not matter, only the normal given.
    const Triangle reversed{unit_triangle[0], unit_triangle[2], unit_triangle[1]};
    EXPECT_TRUE(segment_crosses({0.2, 0.2, 0}, {0.2, 0.2, -1}, reversed, up));
    EXPECT_FALSE(segment_crosses({0.2, 0.2, 0}, {0.2, 0.2, 1}, reversed, up));
}

TEST(SegmentCrosses, ExactlyOneOfTwoPairsIsCutWhenThePlanePassesThroughACentre)
{
    // Voxel centres at z = -1, 0, 1 and a plane z = offset: the pairs (-1, 0) and (0, 1). Within
    // 1e-9 of the segment's length the centre counts as on the plane, hence on the normal's side;
    // beyond that, on the side it lies.
    for (const Vector3d& normal : {up, Vector3d(-up)}) {
        for (double offset : {-1e-6, -1e-12, 0.0, 1e-12, 1e-6}) {
            SCOPED_TRACE(testing::Message() << "normal " << normal.z() << " offset " << offset);
            const Triangle t{Vector3d(-3, -3, offset), Vector3d(5, -3, offset), Vector3d(-3, 5, offset)};
            const Vector3d c(0.25, 0.5, 0.0);
            const bool below = segment_crosses(c - up, c, t, normal), above = segment_crosses(c, c + up, t, normal);
            EXPECT_NE(below, above);
            const bool centre_on_plus_side = std::abs(offset) < 1e-9 || (offset < 0.0) == (normal.z() > 0.0);
            EXPECT_EQ(below, centre_on_plus_side == (normal.z() > 0.0));
        }
    }
}

TEST(SegmentCrosses, ExactlyOneOfTwoPairsAtTiltedPlanesThroughACentre)
{
    // Random planes through (or 1e-12 beside) a voxel centre, each as a triangle around it; the
    // pair segments along each axis the plane is not nearly parallel to. Whatever the rounding
    // says about the centre's side, the two pairs see the same side: exactly one is cut.
    std::mt19937 rng(11);
    std::uniform_real_distribution<double> u(-1.0, 1.0);
    int checked = 0;
    for (int trial = 0; trial < 300; ++trial) {
        const Vector3d n = Vector3d(u(rng), u(rng), u(rng)).normalized();
        const Vector3d a = n.unitOrthogonal(), b = n.cross(a);
        const Vector3d c(u(rng) * 10, u(rng) * 10, u(rng) * 10);
        for (double offset : {-1e-12, 0.0, 1e-12}) {
            const Vector3d o = c + offset * n;
            Triangle t;
            for (int k = 0; k < 3; ++k) {
                const double angle = 2 * M_PI * k / 3 + 0.3;
                t[static_cast<std::size_t>(k)] = o + 4.0 * (std::cos(angle) * a + std::sin(angle) * b);
            }
            for (int axis = 0; axis < 3; ++axis) {
                if (std::abs(n[axis]) < 0.2) continue;
                const Vector3d e = Vector3d::Unit(axis);
                const bool first = segment_crosses(c - e, c, t, n), second = segment_crosses(c, c + e, t, n);
                EXPECT_NE(first, second) << "trial " << trial << " offset " << offset << " axis " << axis;
                ++checked;
            }
        }
    }
    EXPECT_GT(checked, 300);
}

TEST(SegmentCrosses, NoGapAlongAnEdgeTwoTrianglesShare)
{
    // A square split along its diagonal: segments through the diagonal and 1e-12 either side of
    // it are cut by at least one of the two triangles.
    const Triangle a{Vector3d(0, 0, 0), Vector3d(1, 0, 0), Vector3d(1, 1, 0)};
    const Triangle b{Vector3d(0, 0, 0), Vector3d(1, 1, 0), Vector3d(0, 1, 0)};
    const Vector3d across_diagonal = Vector3d(1, -1, 0).normalized();
    for (double s : {0.1, 0.37, 0.5, 0.9})
        for (double offset : {-1e-12, 0.0, 1e-12}) {
            const Vector3d x = Vector3d(s, s, 0) + offset * across_diagonal;
            const Vector3d p = x - 0.5 * up, q = x + 0.5 * up;
            EXPECT_TRUE(segment_crosses(p, q, a, up) || segment_crosses(p, q, b, up)) << s << " " << offset;
        }
}

TEST(SweepSection, AStillBladeGivesJustItsSection)
{
    const ToolShape blade = ToolShape::box({20, 0.5, 8}); // section x in [-10, 10], z in [-4, 4]
    const PlacedShape pose = at(blade, Vector3d::Zero());
    const SweptSurface s = sweep_section(blade, 0.0, pose, pose);
    ASSERT_EQ(s.triangles.size(), 2u); // the rectangle as a fan, nothing swept
    EXPECT_EQ(s.normal, Vector3d::UnitY());
    for (const Triangle& t : s.triangles)
        for (const Vector3d& v : t) {
            EXPECT_EQ(v.y(), 0.0);
            EXPECT_EQ(std::abs(v.x()), 10.0);
            EXPECT_EQ(std::abs(v.z()), 4.0);
        }
    const Eigen::AlignedBox3d b = s.bounds();
    EXPECT_EQ(b.min(), Vector3d(-10, 0, -4));
    EXPECT_EQ(b.max(), Vector3d(10, 0, 4));
    // Area: the section's, once.
    double area = 0.0;
    for (const Triangle& t : s.triangles) area += 0.5 * (t[1] - t[0]).cross(t[2] - t[0]).norm();
    EXPECT_NEAR(area, 160.0, 1e-12);
    for (double x : {-9.9, -3.3, 0.0, 5.1, 9.99})
        for (double z : {-3.9, 0.0, 1.7, 3.99}) {
            const auto [p, q] = across(x, z);
            EXPECT_TRUE(crosses(s, p, q)) << x << " " << z;
        }
    for (const auto& [x, z] : std::vector<XZ>{{10.01, 0.0}, {-10.01, 0.0}, {0.0, 4.01}, {0.0, -4.01}, {15.0, 0.0}}) {
        const auto [p, q] = across(x, z);
        EXPECT_FALSE(crosses(s, p, q)) << x << " " << z;
    }
}

TEST(SweepSection, ABladeTranslatedInItsPlaneCoversEverythingBetweenThePoses)
{
    const ToolShape blade = ToolShape::box({20, 0.5, 8});
    const PlacedShape from = at(blade, Vector3d::Zero()), to = at(blade, Vector3d(30, 0, 0));
    const SweptSurface swept = sweep_section(blade, 0.0, from, to);
    const SweptSurface start = sweep_section(blade, 0.0, from, from), end = sweep_section(blade, 0.0, to, to);
    // Mid-stroke: in neither end section, crossed by the sweep.
    for (double z : {-3.5, 0.3, 2.0}) {
        const auto [p, q] = across(15.0, z);
        EXPECT_FALSE(crosses(start, p, q));
        EXPECT_FALSE(crosses(end, p, q));
        EXPECT_TRUE(crosses(swept, p, q)) << z;
    }
    // Everything the section passed over, and nothing beyond it.
    for (double x = -9.95; x < 40; x += 0.7)
        for (double z : {-3.95, -1.0, 0.0, 2.5, 3.95}) {
            const auto [p, q] = across(x, z);
            EXPECT_TRUE(crosses(swept, p, q)) << x << " " << z;
        }
    for (const auto& [x, z] : std::vector<XZ>{{-10.05, 0.0}, {40.05, 0.0}, {15.0, 4.05}, {15.0, -4.05}, {25.0, 6.0}}) {
        const auto [p, q] = across(x, z);
        EXPECT_FALSE(crosses(swept, p, q)) << x << " " << z;
    }
    const Eigen::AlignedBox3d b = swept.bounds();
    EXPECT_EQ(b.min(), Vector3d(-10, 0, -4));
    EXPECT_EQ(b.max(), Vector3d(40, 0, 4));
}

TEST(SweepSection, ADiagonalStrokeInThePlaneLeavesNoHole)
{
    // Moving up and along at once: a point passed over only at mid-stroke, and the corners of
    // the swept hexagon. The stroke starts and ends on voxel centres' plane y = 0 exactly.
    const ToolShape blade = ToolShape::box({4, 0.5, 2}); // x in [-2, 2], z in [-1, 1]
    const PlacedShape from = at(blade, Vector3d::Zero()), to = at(blade, Vector3d(10, 0, 6));
    const SweptSurface swept = sweep_section(blade, 0.0, from, to);
    // The swept region is the Minkowski sum of the rectangle with the stroke: points on the
    // stroke's line and within the rectangle around any point on it.
    std::mt19937 rng(3);
    std::uniform_real_distribution<double> ux(-3, 13), uz(-2, 8);
    int inside = 0;
    for (int k = 0; k < 2000; ++k) {
        const double x = ux(rng), z = uz(rng);
        // Covered iff some t in [0, 1] puts (x - 10t, z - 6t) in the rectangle.
        const double lo = std::max({0.0, (x - 2) / 10, (z - 1) / 6}), hi = std::min({1.0, (x + 2) / 10, (z + 1) / 6});
        if (std::abs(lo - hi) < 1e-9) continue; // on the boundary
        const auto [p, q] = across(x, z);
        EXPECT_EQ(crosses(swept, p, q), lo < hi) << x << " " << z;
        inside += lo < hi;
    }
    EXPECT_GT(inside, 200);
}

TEST(SweepSection, TheTieRuleHoldsOnTheSweptSurface)
{
    // Voxel centres at y = -1, 0, 1 on a blade's plane (y = offset), including the centre (0, 0, 0)
    // on the diagonal the section's fan shares and one on a swept band: exactly one pair cut.
    const ToolShape blade = ToolShape::box({20, 0.5, 8});
    for (double offset : {-1e-6, -1e-12, 0.0, 1e-12, 1e-6}) {
        const PlacedShape from = at(blade, Vector3d(0, offset, 0)), to = at(blade, Vector3d(30, offset, 0));
        for (const SweptSurface& s : {sweep_section(blade, 0.0, from, from), sweep_section(blade, 0.0, from, to)}) {
            for (const Vector3d& c : {Vector3d(0, 0, 0), Vector3d(5, 0, 2), Vector3d(15, 0, 0), Vector3d(10, 0, 4)}) {
                if (s.triangles.size() == 2 && c.x() > 10) continue; // the still blade does not reach
                const auto [first, second] = pairs_cut(s, c, Vector3d::UnitY());
                EXPECT_NE(first, second) << "offset " << offset << " centre " << c.transpose();
                // The + side (the normal, +y) takes the centre on the surface (to 1e-9 of the spacing).
                EXPECT_EQ(first, offset < 1e-9) << "offset " << offset << " centre " << c.transpose();
            }
        }
    }
}

TEST(SweepSection, TheTieRuleHoldsForATurnedBladeThroughACentre)
{
    // A turned blade whose section (and the fan's shared diagonal) passes through a voxel centre
    // up to rounding: the two pairs must still agree on the centre's side.
    const ToolShape blade = ToolShape::box({20, 0.5, 8});
    std::mt19937 rng(5);
    std::uniform_real_distribution<double> u(-1.0, 1.0);
    int checked = 0;
    for (int trial = 0; trial < 200; ++trial) {
        const Eigen::Quaterniond q(Eigen::AngleAxisd(3 * u(rng), Vector3d(u(rng), u(rng), u(rng)).normalized()));
        const Vector3d centre = Vector3d(std::round(10 * u(rng)), std::round(10 * u(rng)), std::round(10 * u(rng)));
        const PlacedShape pose = at(blade, centre, q);
        const SweptSurface s = sweep_section(blade, 0.0, pose, pose);
        const Vector3d normal = q * Vector3d::UnitY();
        for (int axis = 0; axis < 3; ++axis) {
            if (std::abs(normal[axis]) < 0.2) continue;
            const auto [first, second] = pairs_cut(s, centre, Vector3d::Unit(axis));
            EXPECT_NE(first, second) << "trial " << trial << " axis " << axis;
            ++checked;
        }
    }
    EXPECT_GT(checked, 200);
}

TEST(SweepSection, MarginGrowsTheSectionInItsPlane)
{
    const ToolShape blade = ToolShape::box({20, 0.5, 8});
    const PlacedShape pose = at(blade, Vector3d::Zero());
    const SweptSurface bare = sweep_section(blade, 0.0, pose, pose), grown = sweep_section(blade, 1.0, pose, pose);
    const Eigen::AlignedBox3d b = grown.bounds();
    EXPECT_EQ(b.min(), Vector3d(-11, 0, -5));
    EXPECT_EQ(b.max(), Vector3d(11, 0, 5));
    for (const auto& [x, z] : std::vector<XZ>{{10.5, 0.0}, {-10.5, 2.0}, {3.0, 4.5}, {-7.0, -4.9}}) {
        const auto [p, q] = across(x, z);
        EXPECT_FALSE(crosses(bare, p, q)) << x << " " << z;
        EXPECT_TRUE(crosses(grown, p, q)) << x << " " << z;
    }
    for (const auto& [x, z] : std::vector<XZ>{{11.1, 0.0}, {0.0, 5.1}, {0.0, -5.1}}) {
        const auto [p, q] = across(x, z);
        EXPECT_FALSE(crosses(grown, p, q)) << x << " " << z;
    }
    // In its plane only: the thickness does not grow the section off y = 0.
    for (const Triangle& t : grown.triangles)
        for (const Vector3d& v : t) EXPECT_EQ(v.y(), 0.0);
}

TEST(SweepSection, TurnedBladeCutsAcrossItsOwnYAxis)
{
    // Turned a quarter about z: the tool's y axis is world -x, its section the plane x = 0.
    const ToolShape blade = ToolShape::box({20, 0.5, 8});
    const Eigen::Quaterniond q(Eigen::AngleAxisd(M_PI / 2, Vector3d::UnitZ()));
    const PlacedShape pose = at(blade, Vector3d(1, 2, 3), q);
    const SweptSurface s = sweep_section(blade, 0.0, pose, pose);
    EXPECT_LT((s.normal - Vector3d(-1, 0, 0)).norm(), 1e-15);
    // Tool (5, 0, 2) is world (1, 2 + 5, 3 + 2); tool (12, 0, 0) is beyond the blade.
    EXPECT_TRUE(crosses(s, Vector3d(0.5, 7, 5), Vector3d(1.5, 7, 5)));
    EXPECT_FALSE(crosses(s, Vector3d(0.5, 14, 3), Vector3d(1.5, 14, 3)));
    EXPECT_FALSE(crosses(s, Vector3d(0.5, 7, 5), Vector3d(0.5, 8, 5))); // along the plane
}

TEST(SweepSection, SphereAndMeshSections)
{
    // Sphere: the disc through its centre normal to its y axis, radius + margin (a 24-gon
    // inscribed in that circle).
    const double r = 3.0, m = 0.5;
    const ToolShape ball = ToolShape::sphere(r);
    const PlacedShape pose = at(ball, Vector3d::Zero());
    const SweptSurface s = sweep_section(ball, m, pose, pose);
    EXPECT_EQ(s.triangles.size(), 22u);
    const double inscribed = (r + m) * std::cos(M_PI / 24);
    for (int k = 0; k < 36; ++k) {
        const double a = 2 * M_PI * (k + 0.37) / 36;
        for (double radius : {0.0, 0.5 * r, 0.999 * inscribed}) {
            const auto [p, q] = across(radius * std::cos(a), radius * std::sin(a));
            EXPECT_TRUE(crosses(s, p, q)) << a << " " << radius;
        }
        const auto [p, q] = across(1.001 * (r + m) * std::cos(a), 1.001 * (r + m) * std::sin(a));
        EXPECT_FALSE(crosses(s, p, q)) << a;
    }
    // Mesh tool: the rectangle of its bounds at y = 0, grown by the margin; for a box mesh the
    // same as the box's section.
    const ToolShape box = ToolShape::box({6, 1, 4});
    const ToolShape mesh = ToolShape::from_mesh(box.mesh(0.0));
    const PlacedShape from = at(box, Vector3d::Zero()), to = at(box, Vector3d(3, 0, 1));
    const PlacedShape mesh_from = at(mesh, Vector3d::Zero()), mesh_to = at(mesh, Vector3d(3, 0, 1));
    const SweptSurface a = sweep_section(box, m, from, to), b = sweep_section(mesh, m, mesh_from, mesh_to);
    EXPECT_TRUE(a.bounds().isApprox(b.bounds()));
    for (double x = -4.4; x < 7.5; x += 0.3)
        for (double z = -3.4; z < 4.5; z += 0.3) {
            const auto [p, q] = across(x, z);
            EXPECT_EQ(crosses(a, p, q), crosses(b, p, q)) << x << " " << z;
        }
}
