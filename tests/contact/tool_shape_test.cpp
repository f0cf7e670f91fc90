// Tool shapes: exact signed distances against hand-computed values, gradients against finite
// differences, the mesh tool against the analytic shapes it triangulates, the grown meshes'
// volumes and closedness, and placement in the world.

#include "contact/tool_shape.hpp"
#include "core/error.hpp"

#include <Eigen/Geometry>
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <limits>
#include <map>
#include <random>
#include <utility>

using namespace vox::contact;
using Eigen::Vector3d;

namespace {

const double sqrt2 = std::sqrt(2.0);

/// Central finite difference of the signed distance at p, step h.
Vector3d fd_gradient(const ToolShape& s, const Vector3d& p, double h = 1e-6)
{
    Vector3d g;
    for (int k = 0; k < 3; ++k) {
        const Vector3d e = Vector3d::Unit(k) * h;
        g[k] = (s.signed_distance(p + e) - s.signed_distance(p - e)) / (2 * h);
    }
    return g;
}

/// Random points in the cube [-r, r]^3 (fixed seed).
std::vector<Vector3d> random_points(int count, double r, unsigned seed)
{
    std::mt19937 rng(seed);
    std::uniform_real_distribution<double> u(-r, r);
    std::vector<Vector3d> out;
    for (int i = 0; i < count; ++i) out.emplace_back(u(rng), u(rng), u(rng));
    return out;
}

/// Random points in `box` (fixed seed).
std::vector<Vector3d> random_points(int count, const Eigen::AlignedBox3d& box, unsigned seed)
{
    std::vector<Vector3d> out = random_points(count, 1.0, seed);
    for (Vector3d& p : out) p = box.center() + (0.5 * box.sizes()).cwiseProduct(p);
    return out;
}

/// Enclosed volume of a closed mesh by the divergence theorem: positive when it faces outward.
double signed_volume(const TriangleMesh& m)
{
    double v = 0.0;
    for (const Eigen::Vector3i& t : m.triangles) v += m.positions[t[0]].dot(m.positions[t[1]].cross(m.positions[t[2]]));
    return v / 6.0;
}

/// Every directed edge once and its reverse once: closed (each edge in two triangles) and
/// consistently oriented.
void expect_closed_and_consistent(const TriangleMesh& m)
{
    std::map<std::pair<int, int>, int> directed;
    for (const Eigen::Vector3i& t : m.triangles)
        for (int k = 0; k < 3; ++k) ++directed[{t[k], t[(k + 1) % 3]}];
    for (const auto& [edge, count] : directed) {
        EXPECT_EQ(count, 1) << "edge " << edge.first << "-" << edge.second;
        const auto reverse = directed.find({edge.second, edge.first});
        ASSERT_NE(reverse, directed.end()) << "edge " << edge.first << "-" << edge.second << " is a border";
        EXPECT_EQ(reverse->second, 1);
    }
}

/// Distance from p to the box [-h, h] when p is outside it, computed independently (clamp).
double outside_box_distance(const Vector3d& h, const Vector3d& p)
{
    return (p - p.cwiseMax(-h).cwiseMin(h)).norm();
}

} // namespace

TEST(ToolShape, BoxDistancesAtKnownPoints)
{
    const ToolShape box = ToolShape::box({2, 4, 6}); // half extents 1, 2, 3
    Vector3d g;
    // Inside: the nearest face.
    EXPECT_DOUBLE_EQ(box.signed_distance({0, 0, 0}, &g), -1.0);
    EXPECT_EQ(g, Vector3d(1, 0, 0));
    EXPECT_DOUBLE_EQ(box.signed_distance({0, 1.5, 0}, &g), -0.5);
    EXPECT_EQ(g, Vector3d(0, 1, 0));
    EXPECT_DOUBLE_EQ(box.signed_distance({0.2, -0.3, -2.5}, &g), -0.5);
    EXPECT_EQ(g, Vector3d(0, 0, -1));
    // On faces, edges and corners: zero.
    EXPECT_DOUBLE_EQ(box.signed_distance({1, 0, 0}), 0.0);
    EXPECT_DOUBLE_EQ(box.signed_distance({0.3, -2, 1}), 0.0);
    EXPECT_DOUBLE_EQ(box.signed_distance({1, 2, 0}), 0.0);
    EXPECT_DOUBLE_EQ(box.signed_distance({-1, -2, 3}), 0.0);
    // Outside a face, an edge and a corner.
    EXPECT_DOUBLE_EQ(box.signed_distance({3, 0, 0}, &g), 2.0);
    EXPECT_EQ(g, Vector3d(1, 0, 0));
    EXPECT_DOUBLE_EQ(box.signed_distance({0.5, 0, -4.5}, &g), 1.5);
    EXPECT_EQ(g, Vector3d(0, 0, -1));
    EXPECT_DOUBLE_EQ(box.signed_distance({2, 3, 0}, &g), sqrt2);
    EXPECT_LT((g - Vector3d(1, 1, 0) / sqrt2).norm(), 1e-15);
    EXPECT_DOUBLE_EQ(box.signed_distance({2, 3, 4}, &g), std::sqrt(3.0));
    EXPECT_LT((g - Vector3d(1, 1, 1) / std::sqrt(3.0)).norm(), 1e-15);
    EXPECT_DOUBLE_EQ(box.signed_distance({-4, -2.5, -3.5}, &g), std::sqrt(9 + 0.25 + 0.25));
    EXPECT_LT((g - Vector3d(-3, -0.5, -0.5) / std::sqrt(9.5)).norm(), 1e-15);
}

TEST(ToolShape, BoxDistanceMatchesTheClampFormulaOutside)
{
    const Vector3d size(2, 4, 6);
    const ToolShape box = ToolShape::box(size);
    for (const Vector3d& p : random_points(2000, 6.0, 1)) {
        const double d = box.signed_distance(p);
        if ((p.cwiseAbs().array() <= size.array() / 2).all()) {
            // Inside: minus the distance to the nearest face.
            EXPECT_NEAR(d, -(size / 2 - p.cwiseAbs()).minCoeff(), 1e-15) << p.transpose();
        } else {
            EXPECT_NEAR(d, outside_box_distance(size / 2, p), 1e-14) << p.transpose();
        }
    }
}

TEST(ToolShape, GradientsMatchFiniteDifferences)
{
    const ToolShape shapes[] = {ToolShape::box({2, 4, 6}), ToolShape::scalpel({30, 0.5, 8}), ToolShape::scalpel({4, 1, 8}),
                                ToolShape::sphere(2.5)};
    for (const ToolShape& s : shapes) {
        SCOPED_TRACE(testing::Message() << "kind " << static_cast<int>(s.kind()));
        int inside = 0, outside = 0;
        for (const Vector3d& p : random_points(500, s.bounds(2.0), 2)) {
            Vector3d g;
            const double d = s.signed_distance(p, &g);
            (d < 0 ? inside : outside)++;
            EXPECT_NEAR(g.norm(), 1.0, 1e-12) << p.transpose();
            EXPECT_LT((g - fd_gradient(s, p)).norm(), 1e-5) << p.transpose();
        }
        EXPECT_GT(inside, 5);
        EXPECT_GT(outside, 5);
    }
}

TEST(ToolShape, ScalpelFrontRisesAtFortyFiveDegreesFromThePoint)
{
    // 30 long, 0.5 thick, 8 tall: half extents 15, 0.25, 4. The point (tip) is the bottom front
    // corner (15, 0, -4); the front face climbs to (7, 0, 4); its outward normal is (1, 0, 1)/sqrt2.
    const ToolShape s = ToolShape::scalpel({30, 0.5, 8});
    const Vector3d normal = Vector3d(1, 0, 1) / sqrt2;
    const Vector3d on_front(11, 0, 0); // the middle of the front face
    Vector3d g;
    EXPECT_NEAR(s.signed_distance(on_front), 0.0, 1e-15);
    EXPECT_NEAR(s.signed_distance(on_front + 0.1 * normal, &g), 0.1, 1e-14);
    EXPECT_LT((g - normal).norm(), 1e-15);
    EXPECT_NEAR(s.signed_distance(on_front - 0.1 * normal, &g), -0.1, 1e-14);
    EXPECT_LT((g - normal).norm(), 1e-15);
    // Inside the bounding box but cut away: the point (14, 0, 3) is 6/sqrt2 in front of the face.
    EXPECT_NEAR(s.signed_distance({14, 0, 3}, &g), 6 / sqrt2, 1e-14);
    EXPECT_LT((g - normal).norm(), 1e-15);
    // The tip is a corner of the shape: distance zero there, growing as the distance to it beyond.
    EXPECT_DOUBLE_EQ(s.signed_distance({15, 0, -4}), 0.0);
    EXPECT_NEAR(s.signed_distance({15.3, 0, -4.4}, &g), 0.5, 1e-14);
    EXPECT_LT((g - Vector3d(0.6, 0, -0.8)).norm(), 1e-14);
    // Along the cutting (bottom) edge: the distance is to the bottom face.
    EXPECT_NEAR(s.signed_distance({0, 0, -4.2}, &g), 0.2, 1e-14);
    EXPECT_LT((g - Vector3d(0, 0, -1)).norm(), 1e-15);
    // The back is still square: the top back corner is a box corner.
    EXPECT_NEAR(s.signed_distance({-16, 1.25, 5}), std::sqrt(1 + 1 + 1), 1e-14);
    // Across the thickness: the flat sides.
    EXPECT_NEAR(s.signed_distance({0, 0.75, 0}, &g), 0.5, 1e-15);
    EXPECT_EQ(g, Vector3d(0, 1, 0));
}

TEST(ToolShape, ScalpelShorterThanTallIsAFortyFiveDegreeTriangle)
{
    // 4 long, 8 tall: the 45-degree cut from the point (2, -4) meets the back (x = -2) at
    // z = 0, so the profile is the right triangle (-2, -4), (2, -4), (-2, 0) and nothing of
    // the box above z = 0 remains.
    const ToolShape s = ToolShape::scalpel({4, 1, 8});
    const Vector3d normal = Vector3d(1, 0, 1) / sqrt2;
    Vector3d g;
    // The middle of the slanted face (0, -2) and points in front of and behind it.
    EXPECT_NEAR(s.signed_distance({0, 0, -2}), 0.0, 1e-15);
    EXPECT_NEAR(s.signed_distance(Vector3d(0, 0, -2) + 0.3 * normal, &g), 0.3, 1e-14);
    EXPECT_LT((g - normal).norm(), 1e-15);
    EXPECT_NEAR(s.signed_distance(Vector3d(0, 0, -2) - 0.3 * normal, &g), -0.3, 1e-14);
    EXPECT_LT((g - normal).norm(), 1e-15);
    // The top of the triangle is the back corner (-2, 0): above it is outside.
    EXPECT_NEAR(s.signed_distance({-2, 0, 0}), 0.0, 1e-15);
    EXPECT_NEAR(s.signed_distance({-2, 0, 1}, &g), 1.0, 1e-15);
    EXPECT_LT((g - Vector3d(0, 0, 1)).norm(), 1e-15);
    EXPECT_GT(s.signed_distance({-1.9, 0, 3.9}), 0.0);
    // The tip stays the bottom front corner.
    EXPECT_DOUBLE_EQ(s.signed_distance({2, 0, -4}), 0.0);
    // The bounds hold the triangle and the grown mesh.
    for (double margin : {0.0, 0.5}) {
        const Eigen::AlignedBox3d b = s.bounds(margin);
        EXPECT_NEAR(b.max().z(), margin, 1e-15);
        EXPECT_NEAR(b.min().z(), -4 - margin, 1e-15);
    }
}

TEST(ToolShape, SphereDistanceAndGradientAreExact)
{
    const ToolShape s = ToolShape::sphere(2.0);
    Vector3d g;
    EXPECT_DOUBLE_EQ(s.signed_distance({3, 4, 0}, &g), 3.0);
    EXPECT_LT((g - Vector3d(0.6, 0.8, 0)).norm(), 1e-16);
    EXPECT_DOUBLE_EQ(s.signed_distance({0, 0, -1}, &g), -1.0);
    EXPECT_EQ(g, Vector3d(0, 0, -1));
    EXPECT_DOUBLE_EQ(s.signed_distance({0, 0, 0}, &g), -2.0);
    EXPECT_NEAR(g.norm(), 1.0, 1e-16); // any unit direction at the centre
    EXPECT_DOUBLE_EQ(s.signed_distance({0, 2, 0}), 0.0);
    for (const Vector3d& p : random_points(200, 5.0, 3)) {
        EXPECT_NEAR(s.signed_distance(p, &g), p.norm() - 2.0, 1e-15);
        EXPECT_LT((g - p.normalized()).norm(), 1e-15);
    }
}

TEST(ToolShape, MeshToolMatchesTheAnalyticShapesItTriangulates)
{
    const ToolShape analytic[] = {ToolShape::box({2, 4, 6}), ToolShape::scalpel({30, 0.5, 8}), ToolShape::scalpel({4, 1, 8})};
    for (const ToolShape& a : analytic) {
        SCOPED_TRACE(testing::Message() << "kind " << static_cast<int>(a.kind()));
        const ToolShape m = ToolShape::from_mesh(a.mesh(0.0));
        EXPECT_EQ(m.kind(), ToolShape::Kind::mesh);
        int inside = 0;
        for (const Vector3d& p : random_points(1000, a.bounds(1.0), 4)) {
            Vector3d ga, gm;
            const double da = a.signed_distance(p, &ga), dm = m.signed_distance(p, &gm);
            EXPECT_NEAR(dm, da, 1e-9) << p.transpose();
            EXPECT_EQ(dm < 0.0, da < 0.0) << p.transpose();
            EXPECT_LT((gm - ga).norm(), 1e-9) << p.transpose();
            inside += da < 0.0;
        }
        EXPECT_GT(inside, 10);
        // Bounds of a mesh are those of its vertices.
        EXPECT_LT((m.bounds(0.5).min() - a.bounds(0.5).min()).norm(), 1e-15);
        EXPECT_LT((m.bounds(0.5).max() - a.bounds(0.5).max()).norm(), 1e-15);
    }
}

TEST(ToolShape, MeshToolWithoutTrianglesIsRefused)
{
    EXPECT_THROW((void)ToolShape::from_mesh({}), vox::InputError);
}

TEST(ToolShape, GrownBoxMeshIsTheClosedOutwardPrismAroundTheGrownShape)
{
    const Vector3d size(2, 4, 6);
    const ToolShape box = ToolShape::box(size);
    for (double m : {0.0, 0.25, 1.0}) {
        SCOPED_TRACE(testing::Message() << "margin " << m);
        const TriangleMesh mesh = box.mesh(m);
        EXPECT_EQ(mesh.positions.size(), 8u);
        EXPECT_EQ(mesh.triangles.size(), 12u);
        expect_closed_and_consistent(mesh);
        for (const Vector3d& v : mesh.positions) EXPECT_GE(box.signed_distance(v), m - 1e-12) << v.transpose();
        // Flat faces moved out by m: the box (a + 2m)(b + 2m)(c + 2m), facing outward.
        EXPECT_NEAR(signed_volume(mesh), (size.array() + 2 * m).prod(), 1e-12);
        for (const Eigen::Vector3i& t : mesh.triangles) {
            const Vector3d &a = mesh.positions[t[0]], &b = mesh.positions[t[1]], &c = mesh.positions[t[2]];
            EXPECT_GT((b - a).cross(c - a).dot(a + b + c), 0.0);
        }
    }
}

TEST(ToolShape, GrownScalpelMeshAreaFollowsTheMitredOffsetFormula)
{
    // A convex polygon with flat edges moved out by m (mitred corners) has area
    // A + m P + m^2 sum tan(exterior angle / 2). The scalpel's profile (L long, H tall) has
    // A = L H - H^2 / 2, P = 2 L + sqrt2 H, corners 90, 45 (the point), 135 and 90 degrees:
    // sum tan = 1 + (1 + sqrt2) + (sqrt2 - 1) + 1 = 2 + 2 sqrt2.
    const double length = 30, thickness = 0.5, height = 8;
    const ToolShape s = ToolShape::scalpel({length, thickness, height});
    for (double m : {0.0, 0.5}) {
        SCOPED_TRACE(testing::Message() << "margin " << m);
        const TriangleMesh mesh = s.mesh(m);
        expect_closed_and_consistent(mesh);
        const double area = length * height - height * height / 2 + m * (2 * length + sqrt2 * height) + m * m * (2 + 2 * sqrt2);
        EXPECT_NEAR(signed_volume(mesh), area * (thickness + 2 * m), 1e-11);
        for (const Vector3d& v : mesh.positions) EXPECT_GE(s.signed_distance(v), m - 1e-12) << v.transpose();
    }
}

TEST(ToolShape, GrownSphereMeshIsAClosedOutwardIcosphere)
{
    const double r = 2.0;
    const ToolShape s = ToolShape::sphere(r);
    for (int detail : {0, 1, 2}) {
        for (double m : {0.0, 0.5}) {
            SCOPED_TRACE(testing::Message() << "detail " << detail << " margin " << m);
            const TriangleMesh mesh = s.mesh(m, detail);
            // An icosahedron subdivided `detail` times: 20 * 4^detail faces, 10 * 4^detail + 2 vertices.
            EXPECT_EQ(mesh.triangles.size(), 20u << (2 * detail));
            EXPECT_EQ(mesh.positions.size(), (10u << (2 * detail)) + 2);
            expect_closed_and_consistent(mesh);
            for (const Vector3d& v : mesh.positions) {
                EXPECT_NEAR(v.norm(), r + m, 1e-14);
                EXPECT_NEAR(s.signed_distance(v), m, 1e-14);
            }
            // Inscribed in the ball of radius r + m; the regular icosahedron already holds 60 % of it.
            const double ball = 4.0 / 3.0 * M_PI * std::pow(r + m, 3);
            const double volume = signed_volume(mesh);
            EXPECT_LT(volume, ball);
            EXPECT_GT(volume, 0.6 * ball);
            if (detail == 0) { // the regular icosahedron inscribed in radius R: edge R / sin(2 pi / 5)
                EXPECT_NEAR(volume, 5.0 / 12.0 * (3 + std::sqrt(5.0)) * std::pow((r + m) / std::sin(2 * M_PI / 5), 3), 1e-11);
            }
        }
    }
}

TEST(ToolShape, DistanceBelowTheMarginIsExactlyTheRoundedOffset)
{
    // The outer shape {d < m} is the Minkowski sum with a ball: rounded edges and corners, unlike
    // the mitred mesh. Membership against the clamp construction, at random points and on both
    // sides of the rounded corner.
    const Vector3d size(2, 4, 6), h = size / 2;
    const ToolShape box = ToolShape::box(size);
    const double m = 0.75;
    for (const Vector3d& p : random_points(5000, 4.0, 5)) {
        const bool in_box = (p.cwiseAbs().array() <= h.array()).all();
        const bool in_offset = in_box || outside_box_distance(h, p) < m;
        EXPECT_EQ(box.signed_distance(p) < m, in_offset) << p.transpose();
    }
    const Vector3d corner = h;
    for (const Vector3d& dir : {Vector3d(1, 1, 1), Vector3d(1, 0.2, 3), Vector3d(0, 1, 1)}) {
        const Vector3d u = dir.normalized();
        EXPECT_LT(box.signed_distance(corner + (m - 1e-9) * u), m);
        EXPECT_GT(box.signed_distance(corner + (m + 1e-9) * u), m);
    }
    // The mesh's mitred corner lies outside the rounded offset, at m sqrt3.
    EXPECT_NEAR(box.signed_distance(corner + Vector3d::Constant(m)), m * std::sqrt(3.0), 1e-15);
    // Same for the sphere: the offset of a ball is the ball of radius r + m.
    const ToolShape sphere = ToolShape::sphere(1.5);
    for (const Vector3d& p : random_points(2000, 3.0, 6)) EXPECT_EQ(sphere.signed_distance(p) < m, p.norm() < 1.5 + m);
}

TEST(ToolShape, BoundsHoldTheGrownShape)
{
    // Every point of the grown shape (d < m) lies inside bounds(m), which are tight along each axis.
    const ToolShape shapes[] = {ToolShape::box({2, 4, 6}), ToolShape::scalpel({30, 0.5, 8}), ToolShape::scalpel({4, 1, 8}),
                                ToolShape::sphere(2.5)};
    const double m = 0.5;
    for (const ToolShape& s : shapes) {
        SCOPED_TRACE(testing::Message() << "kind " << static_cast<int>(s.kind()));
        const Eigen::AlignedBox3d b = s.bounds(m);
        const double reach = b.max().cwiseAbs().maxCoeff() + 1.0;
        for (const Vector3d& p : random_points(5000, reach, 7))
            if (s.signed_distance(p) < m) {
                EXPECT_TRUE(b.contains(p)) << p.transpose();
            }
        // Tight: on each side of the bounds, the grown shape's surface reaches it.
        for (int axis = 0; axis < 3; ++axis) {
            for (double sign : {-1.0, 1.0}) {
                const double face = sign > 0 ? b.max()[axis] : b.min()[axis];
                // The shape's extreme vertices along the axis lie exactly m inside the face.
                double best = std::numeric_limits<double>::infinity();
                for (const Vector3d& v : s.mesh(0.0, 3).positions) best = std::min(best, std::abs(face - v[axis]));
                EXPECT_NEAR(best, m, 1e-12) << "axis " << axis << " sign " << sign;
            }
        }
    }
}

TEST(PlacedShape, DistanceIsInvariantAndGradientTurnsWithThePlacement)
{
    const ToolShape shapes[] = {ToolShape::box({2, 4, 6}), ToolShape::scalpel({30, 0.5, 8}), ToolShape::sphere(2.5)};
    const Eigen::Quaterniond q(Eigen::AngleAxisd(0.8, Vector3d(1, -2, 0.5).normalized()));
    const Vector3d position(10, -20, 5);
    for (const ToolShape& s : shapes) {
        SCOPED_TRACE(testing::Message() << "kind " << static_cast<int>(s.kind()));
        const PlacedShape placed{&s, position, q};
        const double reach = s.bounds(2.0).max().cwiseAbs().maxCoeff();
        for (const Vector3d& local : random_points(300, reach, 8)) {
            const Vector3d world = position + q * local;
            Vector3d gl, gw;
            const double dl = s.signed_distance(local, &gl);
            EXPECT_NEAR(placed.signed_distance(world, &gw), dl, 1e-12);
            EXPECT_LT((gw - q * gl).norm(), 1e-12);
            // The world gradient is the derivative in world coordinates.
            Vector3d fd;
            for (int k = 0; k < 3; ++k) {
                const Vector3d e = Vector3d::Unit(k) * 1e-6;
                fd[k] = (placed.signed_distance(world + e) - placed.signed_distance(world - e)) / 2e-6;
            }
            EXPECT_LT((fd - gw).norm(), 1e-5) << local.transpose();
        }
    }
}

TEST(PlacedShape, WorldBoundsHoldTheMovedMeshAndTheGrownShape)
{
    const ToolShape shapes[] = {ToolShape::box({2, 4, 6}), ToolShape::sphere(2.5), ToolShape::scalpel({30, 0.5, 8})};
    const Eigen::Quaterniond q(Eigen::AngleAxisd(1.1, Vector3d(0.3, 1, -0.7).normalized()));
    const Vector3d position(-3, 4, 12);
    for (const ToolShape& s : shapes) {
        SCOPED_TRACE(testing::Message() << "kind " << static_cast<int>(s.kind()));
        const PlacedShape placed{&s, position, q};
        // The flat-faced meshes with margin stick out at the scalpel's point (a mitred 45-degree
        // corner), so compare with the mesh at margin 0 for every shape and the grown mesh for
        // the box and sphere, whose grown mesh lies in the grown bounds.
        for (double m : {0.0, 0.5}) {
            const Eigen::AlignedBox3d b = placed.world_bounds(m);
            const double slack = 1e-12;
            const Eigen::AlignedBox3d loose(b.min() - Vector3d::Constant(slack), b.max() + Vector3d::Constant(slack));
            const TriangleMesh mesh = s.mesh(s.kind() == ToolShape::Kind::scalpel ? 0.0 : m);
            for (const Vector3d& v : mesh.positions) EXPECT_TRUE(loose.contains(position + q * v)) << v.transpose();
            // And the exact grown shape, sampled.
            for (const Vector3d& local : random_points(3000, s.bounds(m).max().cwiseAbs().maxCoeff(), 9))
                if (s.signed_distance(local) < m) {
                    EXPECT_TRUE(loose.contains(position + q * local)) << local.transpose();
                }
        }
        // Unturned, the world bounds are the tool bounds moved.
        const PlacedShape moved{&s, position, Eigen::Quaterniond::Identity()};
        EXPECT_LT((moved.world_bounds(0.5).min() - (s.bounds(0.5).min() + position)).norm(), 1e-14);
        EXPECT_LT((moved.world_bounds(0.5).max() - (s.bounds(0.5).max() + position)).norm(), 1e-14);
    }
}

TEST(ToolShape, ShadowAreasAgainstClosedForms)
{
    // A box's shadow along a unit n is sum |n_i| times the face across axis i, and its outline's
    // perimeter twice the sum of its edges' lengths across n; grown by a margin r, the shadow
    // gains perimeter x r + pi r^2 (Steiner). A sphere's is pi (R + r)^2, a cylinder's seen along
    // its axis pi R^2 (the circumscribed 48-gon: at most 0.3 % more), a mesh tool's that of its
    // shape.
    const Vector3d size(16, 1, 8);
    const ToolShape box = ToolShape::box(size), as_mesh = ToolShape::from_mesh(box.mesh(0.0, 1));
    for (const Vector3d& along : {Vector3d(0, 0, 1), Vector3d(1, 2, 3).normalized(), Vector3d(-0.3, 0.1, -0.9).normalized()}) {
        double area = 0.0, perimeter = 0.0;
        for (int i = 0; i < 3; ++i) {
            area += std::abs(along[i]) * size[(i + 1) % 3] * size[(i + 2) % 3];
            perimeter += 2.0 * size[i] * std::sqrt(std::max(0.0, 1.0 - along[i] * along[i]));
        }
        for (const double r : {0.0, 0.25}) {
            const double expected = area + perimeter * r + M_PI * r * r;
            EXPECT_NEAR(box.shadow_area(along, r), expected, 1e-9 * expected) << along.transpose() << ", " << r;
            EXPECT_NEAR(as_mesh.shadow_area(3.0 * along, r), expected, 1e-9 * expected) << along.transpose() << ", " << r;
        }
    }
    EXPECT_NEAR(ToolShape::sphere(2.0).shadow_area(Vector3d(1, 1, 0), 0.5), M_PI * 6.25, 1e-12);
    const double disc = ToolShape::cylinder(3.0, 10.0).shadow_area(Vector3d(0, 0, -1));
    EXPECT_GE(disc, M_PI * 9.0);
    EXPECT_LE(disc, 1.003 * M_PI * 9.0);
    EXPECT_NEAR(ToolShape::cylinder(3.0, 10.0).shadow_area(Vector3d(1, 0, 0)), 60.0, 0.003 * 60.0); // the side: 2 R L
    // A scalpel seen across its flat sides: its profile (16 x 8 with the front's 8 x 8 corner cut).
    EXPECT_NEAR(ToolShape::scalpel(size).shadow_area(Vector3d(0, 1, 0)), 16.0 * 8.0 - 32.0, 1e-9);
    EXPECT_EQ(box.shadow_area(Vector3d::Zero()), INFINITY);
}

TEST(ToolShape, ASegmentReachingIntoTheGrownShapeHasBothEndsWithinItsReachBand)
{
    // Random segments around a ball, a box and a blade: each one whose ends are both outside the
    // shape grown by the margin but that dips into it (its distance sampled finely along it) has
    // both ends within reach_band_mm of the grown shape. The band is the bound the contact patch
    // leaves its other edges out by, so no edge that can be pressed is left out.
    const double margin = 0.25;
    const ToolShape shapes[] = {ToolShape::sphere(2.0), ToolShape::box({6, 6, 4}), ToolShape::scalpel({16, 1, 8})};
    std::mt19937 rng(7);
    std::uniform_real_distribution<double> unit(-1.0, 1.0), length(0.1, 2.0);
    for (const ToolShape& shape : shapes) {
        const Eigen::AlignedBox3d around = shape.bounds(margin + 2.0);
        int reaching = 0;
        double closest_to_band = INFINITY;
        for (const Vector3d& a : random_points(150000, around, 11)) {
            const Vector3d direction = Vector3d(unit(rng), unit(rng), unit(rng)).normalized();
            const double l = length(rng);
            const Vector3d b = a + l * direction;
            const double e_a = shape.signed_distance(a) - margin, e_b = shape.signed_distance(b) - margin;
            if (!(e_a >= 0.0 && e_b >= 0.0) || 0.5 * (e_a + e_b - l) >= 0.0) continue; // outside by the Lipschitz bound alone
            double deepest = INFINITY;
            for (int k = 1; k < 400; ++k) deepest = std::min(deepest, shape.signed_distance(a + (k / 400.0) * (b - a)) - margin);
            if (!(deepest < 0.0)) continue;
            ++reaching;
            const double band = shape.reach_band_mm(margin, l);
            EXPECT_LT(std::max(e_a, e_b), band) << "segment " << a.transpose() << " -> " << b.transpose();
            closest_to_band = std::min(closest_to_band, band - std::max(e_a, e_b));
        }
        EXPECT_GT(reaching, 100) << "too few segments reached in to test the band";
        std::printf("kind %d: %d segments reach in; their farther end is at least %.4f mm inside the band\n", static_cast<int>(shape.kind()), reaching,
                    closest_to_band);
    }
    // For a ball the band is far thinner than the distance's Lipschitz bound (the segment's length).
    EXPECT_LT(ToolShape::sphere(2.0).reach_band_mm(margin, 1.0), 0.25);
}
