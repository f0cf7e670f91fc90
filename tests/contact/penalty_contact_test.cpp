// Penalty contact: a flat patch under a flat tool gives f = k d A / 1 cm^2 and the pressure k d,
// the reaction and torque on the tool balance the point forces, and the per-point stiffness is
// the derivative of the force with respect to the depth.

#include "contact/penalty_contact.hpp"
#include "contact/swept_contact.hpp"

#include <Eigen/Geometry>
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <span>
#include <vector>

using namespace vox::contact;
using Eigen::Vector3d;

namespace {

/// A 20 x 20 x 4 mm plate tool; its bottom face is at z = position.z - 2.
const ToolShape plate = ToolShape::box({20, 20, 4});

/// A 10 x 10 grid of surface points on z = 0, 1 mm apart, centred on (cx, cy), 1 mm^2 each,
/// outward normal +z (the object lies below).
struct Patch {
    std::vector<Vector3d> points, normals;
    std::vector<double> areas;
    Patch(double cx = 0.0, double cy = 0.0)
    {
        for (int i = 0; i < 10; ++i)
            for (int j = 0; j < 10; ++j) {
                points.emplace_back(cx - 4.5 + i, cy - 4.5 + j, 0.0);
                normals.emplace_back(0, 0, 1);
                areas.push_back(1.0);
            }
    }
    void add(const Vector3d& p, const Vector3d& n, double a)
    {
        points.push_back(p);
        normals.push_back(n);
        areas.push_back(a);
    }
    [[nodiscard]] ContactResult contact(const PlacedShape& tool, const ContactParameters& c) const
    {
        return penalty_contact(tool, c, points, areas, normals);
    }
};

/// The plate placed so that the patch (z = 0) is `depth` inside its outer shape.
PlacedShape plate_pressing(double depth, const ContactParameters& c, double x = 0.0, double y = 0.0)
{
    return PlacedShape{&plate, Vector3d(x, y, c.margin_mm - depth + 2.0), Eigen::Quaterniond::Identity()};
}

} // namespace

TEST(PenaltyContact, FlatPatchUnderAFlatToolPushesWithKDAPerSquareCentimetre)
{
    ContactParameters c;
    c.margin_mm = 1.0;
    c.stiffness_n_per_mm = 7.0;
    const double depth = 0.25, area = 100.0; // mm, mm^2
    const Patch patch;
    const ContactResult r = patch.contact(plate_pressing(depth, c), c);
    ASSERT_EQ(r.points.size(), 100u);
    const double total = c.stiffness_n_per_mm * depth * area / 100.0; // N
    Vector3d on_points = Vector3d::Zero();
    for (const PointContact& p : r.points) {
        EXPECT_DOUBLE_EQ(p.depth_mm, depth);
        EXPECT_EQ(p.normal, Vector3d(0, 0, -1));
        EXPECT_DOUBLE_EQ(p.stiffness_n_per_mm, c.stiffness_n_per_mm / 100.0);
        EXPECT_LT((p.force_n - Vector3d(0, 0, -c.stiffness_n_per_mm * depth / 100.0)).norm(), 1e-16);
        EXPECT_FALSE(p.inside_inner);
        on_points += p.force_n;
    }
    EXPECT_LT((on_points - Vector3d(0, 0, -total)).norm(), 1e-14 * total);
    EXPECT_LT((r.force_on_tool_n - Vector3d(0, 0, total)).norm(), 1e-14 * total);
    EXPECT_DOUBLE_EQ(r.area_mm2, area);
    // k d over 1 cm^2: N / mm^2 = 1e6 Pa.
    EXPECT_NEAR(r.pressure_pa, 1e6 * c.stiffness_n_per_mm * depth / 100.0, 1e-9);
    EXPECT_FALSE(r.inner_reaches_surface());
    // Linear in the depth and independent of the resolution: twice as deep, twice the force.
    const ContactResult deeper = patch.contact(plate_pressing(2 * depth, c), c);
    EXPECT_NEAR(deeper.force_on_tool_n.z(), 2 * total, 1e-14 * total);
    EXPECT_NEAR(deeper.pressure_pa, 2 * r.pressure_pa, 1e-9);
}

TEST(PenaltyContact, PressureDoesNotDependOnTheSampling)
{
    // The same 100 mm^2 as 400 points of 0.25 mm^2: the same force and pressure.
    ContactParameters c;
    std::vector<Vector3d> points, normals;
    std::vector<double> areas;
    for (int i = 0; i < 20; ++i)
        for (int j = 0; j < 20; ++j) {
            points.emplace_back(-4.75 + 0.5 * i, -4.75 + 0.5 * j, 0.0);
            normals.emplace_back(0, 0, 1);
            areas.push_back(0.25);
        }
    const PlacedShape tool = plate_pressing(0.4, c);
    const ContactResult fine = penalty_contact(tool, c, points, areas, normals);
    const ContactResult coarse = Patch().contact(tool, c);
    EXPECT_NEAR(fine.force_on_tool_n.z(), coarse.force_on_tool_n.z(), 1e-13 * coarse.force_on_tool_n.z());
    EXPECT_NEAR(fine.pressure_pa, coarse.pressure_pa, 1e-8);
    EXPECT_DOUBLE_EQ(fine.area_mm2, coarse.area_mm2);
}

TEST(PenaltyContact, PointsOutsideTheMarginAreIgnored)
{
    ContactParameters c;
    c.margin_mm = 1.0;
    Patch patch;
    const PlacedShape tool = plate_pressing(0.25, c); // bottom face at z = 0.75
    patch.add({0, 0, -0.25}, {0, 0, 1}, 5.0);       // exactly at the margin: depth 0
    patch.add({1, 1, -0.5}, {0, 0, 1}, 5.0);        // beyond the margin
    patch.add({50, 0, 0.75}, {0, 0, 1}, 5.0);       // far beside the tool
    patch.add({10.9, 10.9, 0.75}, {0, 0, 1}, 5.0);  // inside the grown bounds, outside the rounded edge (0.9 sqrt2 > 1)
    patch.add({10.5, 10.5, 0.75}, {0, 0, 1}, 5.0);  // inside the rounded edge (0.5 sqrt2 < 1): counts
    ASSERT_NEAR(tool.signed_distance(patch.points[100]), 1.0, 1e-15);
    const ContactResult r = patch.contact(tool, c);
    ASSERT_EQ(r.points.size(), 101u);
    EXPECT_EQ(r.points.back().point, 104u);
    EXPECT_NEAR(r.points.back().depth_mm, 1.0 - 0.5 * std::sqrt(2.0), 1e-15);
    EXPECT_DOUBLE_EQ(r.area_mm2, 105.0);
    for (const PointContact& p : r.points) EXPECT_GT(p.depth_mm, 0.0);
    // Nothing within reach: no force, no pressure.
    const ContactResult none = patch.contact(plate_pressing(-0.5, c), c);
    EXPECT_TRUE(none.points.empty());
    EXPECT_EQ(none.force_on_tool_n, Vector3d::Zero());
    EXPECT_EQ(none.pressure_pa, 0.0);
    EXPECT_EQ(none.area_mm2, 0.0);
}

TEST(PenaltyContact, TorqueIsZeroForACentredPatchAndRCrossFOffCentre)
{
    ContactParameters c;
    c.stiffness_n_per_mm = 5.0;
    const double depth = 0.3;
    const Patch patch; // centred on the origin
    const ContactResult centred = patch.contact(plate_pressing(depth, c), c);
    const double f = c.stiffness_n_per_mm * depth; // over 100 mm^2
    EXPECT_LT(centred.torque_on_tool_n_mm.norm(), 1e-12 * f);
    // The tool moved by (3, -2) in its plane: the patch's centroid is at r = (-3, 2, -h) from the
    // tool's origin and the uniform load acts there: torque = r x F.
    const PlacedShape off = plate_pressing(depth, c, 3.0, -2.0);
    const ContactResult r = patch.contact(off, c);
    ASSERT_EQ(r.points.size(), 100u);
    const Vector3d arm = Vector3d::Zero() - off.position;
    const Vector3d expected = arm.cross(r.force_on_tool_n);
    EXPECT_LT((r.force_on_tool_n - Vector3d(0, 0, f)).norm(), 1e-13 * f);
    EXPECT_LT((r.torque_on_tool_n_mm - expected).norm(), 1e-12 * expected.norm());
    EXPECT_NEAR(r.torque_on_tool_n_mm.x(), 2 * f, 1e-12 * f);
    EXPECT_NEAR(r.torque_on_tool_n_mm.y(), 3 * f, 1e-12 * f);
    // And the moment balance point by point: the tool's torque is minus the points' moments.
    Vector3d moments = Vector3d::Zero();
    for (const PointContact& p : r.points) moments += (patch.points[p.point] - off.position).cross(p.force_n);
    EXPECT_LT((r.torque_on_tool_n_mm + moments).norm(), 1e-12 * expected.norm());
}

TEST(PenaltyContact, ZeroNormalFallsBackToTheToolNormal)
{
    ContactParameters c;
    c.margin_mm = 1.0;
    c.stiffness_n_per_mm = 4.0;
    const PlacedShape tool{&plate, Vector3d(0, 0, 10), Eigen::Quaterniond(Eigen::AngleAxisd(M_PI / 2, Vector3d::UnitZ()))};
    // Beside the plate's side face (its local x = 10, turned to world y = 10), 0.3 mm off it.
    const std::vector<Vector3d> points{{0, 10.3, 10}, {0, 10.3, 10}};
    const std::vector<Vector3d> normals{Vector3d::Zero(), Vector3d(0, 0, 1)};
    const std::vector<double> areas{2.0, 2.0};
    const ContactResult r = penalty_contact(tool, c, points, areas, normals);
    ASSERT_EQ(r.points.size(), 2u);
    const double magnitude = c.stiffness_n_per_mm / 100.0 * 2.0 * 0.7;
    // Without a normal: pushed away from the tool, along its face normal (world +y).
    EXPECT_LT((r.points[0].normal - Vector3d(0, 1, 0)).norm(), 1e-15);
    EXPECT_LT((r.points[0].force_n - magnitude * Vector3d(0, 1, 0)).norm(), 1e-15);
    // With one: along minus the object's normal, whatever the tool's face says.
    EXPECT_EQ(r.points[1].normal, Vector3d(0, 0, -1));
    EXPECT_LT((r.points[1].force_n - magnitude * Vector3d(0, 0, -1)).norm(), 1e-15);
    EXPECT_NEAR(r.points[1].depth_mm, 0.7, 1e-14);
}

TEST(PenaltyContact, InsideInnerExactlyWhenTheDistanceIsNegative)
{
    // Points on the plate's axis across its bottom face (z = 0.75) at offsets -1e-12, 0, 1e-12.
    ContactParameters c;
    c.margin_mm = 1.0;
    const PlacedShape tool = plate_pressing(0.25, c);
    std::vector<Vector3d> points, normals;
    std::vector<double> areas;
    for (double offset : {-0.5, -1e-12, 0.0, 1e-12, 0.5, 1.9}) {
        points.emplace_back(0.3, -0.2, 0.75 + offset);
        normals.emplace_back(0, 0, 1);
        areas.push_back(1.0);
    }
    const ContactResult r = penalty_contact(tool, c, points, areas, normals);
    ASSERT_EQ(r.points.size(), points.size());
    const bool expected[] = {false, false, false, true, true, true};
    for (std::size_t i = 0; i < points.size(); ++i) {
        SCOPED_TRACE(testing::Message() << "point " << i);
        const double distance = tool.signed_distance(points[i]);
        EXPECT_EQ(r.points[i].inside_inner, distance < 0.0);
        EXPECT_EQ(r.points[i].inside_inner, expected[i]);
        EXPECT_DOUBLE_EQ(r.points[i].depth_mm, c.margin_mm - distance);
    }
    EXPECT_DOUBLE_EQ(tool.signed_distance(points[2]), 0.0); // on the face: not inside
    EXPECT_TRUE(r.inner_reaches_surface());
}

TEST(PenaltyContact, StiffnessIsTheDerivativeOfTheForceWithDepth)
{
    // Press a sphere into a random curved cloud of points: moving the tool by h along a direction
    // changes each point's force by the finite difference stiffness * d(depth).
    ContactParameters c;
    c.margin_mm = 0.5;
    c.stiffness_n_per_mm = 3.0;
    const ToolShape ball = ToolShape::sphere(4.0);
    std::vector<Vector3d> points, normals;
    std::vector<double> areas;
    for (int i = 0; i < 12; ++i)
        for (int j = 0; j < 12; ++j) {
            const double x = -3.3 + 0.6 * i, y = -3.3 + 0.6 * j;
            points.emplace_back(x, y, 0.02 * x * x - 0.01 * y * y);
            normals.push_back(Vector3d(-0.04 * x, 0.02 * y, 1).normalized());
            areas.push_back(0.36);
        }
    const PlacedShape tool{&ball, Vector3d(0.2, -0.1, 4.1), Eigen::Quaterniond::Identity()};
    const ContactResult r = penalty_contact(tool, c, points, areas, normals);
    ASSERT_GT(r.points.size(), 20u);
    const double h = 1e-6;
    PlacedShape up = tool, down = tool;
    up.position.z() += h;
    down.position.z() -= h;
    for (const PointContact& p : r.points) {
        const double ddepth = -(tool.signed_distance(points[p.point] - Vector3d(0, 0, h)) -
                                tool.signed_distance(points[p.point] + Vector3d(0, 0, h))) / (2 * h);
        const ContactResult a = penalty_contact(up, c, std::span(&points[p.point], 1), std::span(&areas[p.point], 1),
                                                std::span(&normals[p.point], 1));
        const ContactResult b = penalty_contact(down, c, std::span(&points[p.point], 1), std::span(&areas[p.point], 1),
                                                std::span(&normals[p.point], 1));
        ASSERT_EQ(a.points.size(), 1u);
        ASSERT_EQ(b.points.size(), 1u);
        const Vector3d dforce = (a.points[0].force_n - b.points[0].force_n) / (2 * h);
        EXPECT_LT((dforce - p.stiffness_n_per_mm * ddepth * p.normal).norm(), 1e-6 * p.stiffness_n_per_mm);
        // Raising the tool makes every point shallower.
        EXPECT_LT(ddepth, 0.0);
        EXPECT_LT((p.force_n - p.stiffness_n_per_mm * p.depth_mm * p.normal).norm(), 1e-15);
        EXPECT_NEAR(p.normal.norm(), 1.0, 1e-15);
    }
}

TEST(PenaltyTotals, AreThePointListsSumsForAnyPose)
{
    // The 1 kHz loop's allocation-free totals and the per-point contact are one model: same force,
    // torque, area, load area, pressure and inner-shape test, for a blade turned at random over
    // a random cloud of points with random normals and areas.
    const ToolShape blade = ToolShape::box({12, 1, 6});
    std::srand(7);
    auto uniform = [](double lo, double hi) { return lo + (hi - lo) * std::rand() / static_cast<double>(RAND_MAX); };
    SurfacePoints cloud(400);
    std::vector<Vector3d> points, normals;
    std::vector<double> areas;
    for (std::size_t i = 0; i < cloud.capacity(); ++i) {
        const Vector3d p(uniform(-8, 8), uniform(-3, 3), uniform(-5, 5));
        const Vector3d n = i % 7 == 0 ? Vector3d::Zero() : Vector3d(uniform(-1, 1), uniform(-1, 1), uniform(-1, 1)).normalized();
        const double a = uniform(0.1, 2.0);
        cloud.positions_mm[i] = p, cloud.normals[i] = n, cloud.areas_mm2[i] = a;
        points.push_back(p), normals.push_back(n), areas.push_back(a);
    }
    cloud.count = cloud.capacity();
    int touching = 0;
    for (int trial = 0; trial < 20; ++trial) {
        PlacedShape tool{&blade, Vector3d(uniform(-1, 1), uniform(-1, 1), uniform(-1, 1)),
                         Eigen::Quaterniond(Eigen::AngleAxisd(uniform(0, 3), Vector3d(uniform(-1, 1), 1, uniform(-1, 1)).normalized()))};
        const ContactParameters parameters{0.5, 5.0};
        const ContactResult list = penalty_contact(tool, parameters, points, areas, normals);
        const ContactTotals totals = penalty_totals(tool, parameters, cloud);
        touching += list.points.size() > 10;
        EXPECT_LT((list.force_on_tool_n - totals.force_on_tool_n).norm(), 1e-12 * (1.0 + list.force_on_tool_n.norm()));
        EXPECT_LT((list.torque_on_tool_n_mm - totals.torque_on_tool_n_mm).norm(), 1e-12 * (1.0 + list.torque_on_tool_n_mm.norm()));
        EXPECT_NEAR(list.area_mm2, totals.area_mm2, 1e-12 * (1.0 + list.area_mm2));
        EXPECT_NEAR(list.load_area_mm2, totals.load_area_mm2, 1e-12 * (1.0 + list.area_mm2));
        EXPECT_NEAR(list.pressure_pa, totals.pressure_pa, 1e-9 * (1.0 + list.pressure_pa));
        EXPECT_EQ(list.inner_reaches_surface(), totals.inner_reaches_surface);
        Eigen::Matrix3d stiffness = Eigen::Matrix3d::Zero();
        for (const PointContact& c : list.points) stiffness += c.stiffness_n_per_mm * c.normal * c.normal.transpose();
        EXPECT_LT((stiffness - totals.stiffness_n_per_mm).norm(), 1e-12 * (1.0 + stiffness.norm()));
    }
    EXPECT_EQ(touching, 20); // every pose touches many points: the comparison is not vacuous
}

TEST(ContinuousPenalty, MeanPenetrationOverAStep)
{
    double inside = -1.0;
    EXPECT_DOUBLE_EQ(mean_penetration(0.2, 0.4, inside), 0.3); // inside throughout
    EXPECT_DOUBLE_EQ(inside, 1.0);
    EXPECT_DOUBLE_EQ(mean_penetration(-0.3, -0.1, inside), 0.0); // outside throughout
    EXPECT_DOUBLE_EQ(inside, 0.0);
    // Entering at t = 1/4 and reaching 0.3: the mean of the ramp over [1/4, 1] is 0.15 * 3/4.
    EXPECT_NEAR(mean_penetration(-0.1, 0.3, inside), 0.1125, 1e-15);
    EXPECT_DOUBLE_EQ(inside, 0.75);
    // Leaving is the same ramp backwards.
    EXPECT_NEAR(mean_penetration(0.3, -0.1, inside), 0.1125, 1e-15);
}

TEST(ContinuousPenalty, TheImpulseOfAnApproachIsExactWhereverTheStepsFall)
{
    // The plate comes down at 40 mm/s onto the patch and keeps going for 60 ms; the contact force
    // is taken once a step of 10 ms. Integrated over each step, the force times dt adds up to the
    // exact impulse of the penalty (k A / 1 cm^2 times the integral of the depth) wherever the
    // steps fall; the discrete force, taken at each step's end as if the plate had been there all
    // step, overshoots it by half a step of travel (here a sixth).
    const ContactParameters c{1.0, 5.0};
    const Patch patch;
    const double speed = 40.0, dt = 0.01, k_area = c.stiffness_n_per_mm / 100.0 * 100.0; // N/mm over the 1 cm^2 patch
    auto depth_at = [&](double t) { return speed * t; };                                   // contact begins at t = 0
    auto pose = [&](double t) { return plate_pressing(depth_at(t), c); };
    const double end = 0.06, exact = k_area * 0.5 * speed * end * end; // N s
    double worst_continuous = 0.0, least_discrete = 1e9, first_discrete = 0.0, first_continuous = 0.0;
    for (double phase : {0.1, 0.35, 0.6, 0.85}) {
        double continuous = 0.0, discrete = 0.0;
        bool first = true;
        double t0 = -2 * dt;
        for (double t = t0 + phase * dt;; t += dt) {
            const double t1 = std::min(t, end);
            const PlacedShape from = pose(t0), to = pose(t1);
            const double f_cont = penalty_contact(to, c, patch.points, patch.areas, patch.normals, &from).force_on_tool_n.z();
            const double f_disc = patch.contact(to, c).force_on_tool_n.z();
            continuous += f_cont * (t1 - t0);
            discrete += f_disc * (t1 - t0);
            if (first && f_disc > 0.0) {
                first = false;
                first_discrete = f_disc;
                first_continuous = f_cont;
            }
            if (t1 >= end) break;
            t0 = t1;
        }
        worst_continuous = std::max(worst_continuous, std::abs(continuous - exact) / exact);
        least_discrete = std::min(least_discrete, (discrete - exact) / exact);
        // The first step in contact: the continuous force is the discrete one times half the
        // share of the step in contact, so it starts at most half as high.
        EXPECT_LE(first_continuous, 0.5 * first_discrete + 1e-12);
    }
    EXPECT_LT(worst_continuous, 1e-9);
    EXPECT_GT(least_discrete, 0.1);
}

// ---------------------------------------------------------------------------------------------
// Edges (the Is-XFEM paper's edge-edge penalty, equation 19).
// ---------------------------------------------------------------------------------------------

namespace {

/// A flat 10 x 10 mm patch on z = 0 of 2 mm squares, each split along its diagonal: vertices at
/// x, y in {-4, -2, 0, 2, 4}, 4 mm^2 each, outward normal +z.
struct CoarsePatch {
    std::vector<Vector3d> points, normals;
    std::vector<double> areas;
    std::vector<Eigen::Vector3i> triangles;
    CoarsePatch()
    {
        for (int i = 0; i < 5; ++i)
            for (int j = 0; j < 5; ++j) {
                points.emplace_back(-4.0 + 2 * i, -4.0 + 2 * j, 0.0);
                normals.emplace_back(0, 0, 1);
                areas.push_back(4.0);
            }
        for (int i = 0; i < 4; ++i)
            for (int j = 0; j < 4; ++j) {
                const int a = 5 * i + j, b = 5 * (i + 1) + j, c = b + 1, d = a + 1;
                triangles.emplace_back(a, b, c);
                triangles.emplace_back(a, c, d);
            }
    }
};

/// A blade 0.2 mm thick across x, 20 mm long along y, over the coarse patch, pressed with
/// 5 N/mm per cm^2 and no margin.
struct EdgePenalty : ::testing::Test {
    const ToolShape blade = ToolShape::box({0.2, 20, 10});
    const CoarsePatch patch;
    const ContactParameters parameters{0.0, 5.0};
    /// Centred on x, its edge `depth` below z = 0.
    [[nodiscard]] PlacedShape at(double x, double depth) const { return {&blade, Vector3d(x, 0, 5.0 - depth), Eigen::Quaterniond::Identity()}; }
    [[nodiscard]] ContactResult touch(const PlacedShape& tool, bool edges, const PlacedShape* from = nullptr) const
    {
        return penalty_contact(tool, parameters, patch.points, patch.areas, patch.normals, from,
                               edges ? std::span<const Eigen::Vector3i>(patch.triangles) : std::span<const Eigen::Vector3i>());
    }
};

} // namespace

TEST_F(EdgePenalty, ABladeEdgeBetweenTwoRowsOfVerticesPressesTheEdgesItCrosses)
{
    // The blade lies between the vertex columns x = 0 and x = 2: no vertex is inside it, but the
    // 5 rows' horizontal edges and the 4 squares' diagonals from x = 0 to x = 2 cross it (9
    // edges). Each is inside over 0.2 mm of its 2 mm run across (share 0.1), 0.05 mm deep: it
    // stands for 0.1 x (4 + 4) / 6 mm^2 and is pushed with k d a.
    const PlacedShape between = at(1.0, 0.05);
    EXPECT_TRUE(touch(between, false).points.empty()); // the blade falls between the vertices
    const ContactResult with = touch(between, true);
    const double area = 0.1 * 8.0 / 6.0, force = 5.0 / 100.0 * area * 0.05;
    EXPECT_EQ(with.points.size(), 2u * 9u);
    EXPECT_NEAR(-with.force_on_tool_n.z(), -9.0 * force, 1e-4 * 9.0 * force); // pushed into the object, along -normal (the share to 0.1 um)
    EXPECT_NEAR(with.force_on_tool_n.head<2>().norm(), 0.0, 1e-12);
    EXPECT_NEAR(with.area_mm2, 9.0 * area, 1e-4 * 9.0 * area);
    EXPECT_NEAR(with.pressure_pa, 1e6 * force / area, 1e-3 * 1e6 * force / area); // k d: the same as a point's
    EXPECT_TRUE(with.inner_reaches_surface());
    // Each edge's force goes to its ends by where the point on it is: about the middle (the
    // depth is the same over the middle 0.1 mm of the blade's thickness), about half each.
    for (const PointContact& c : with.points) EXPECT_NEAR(c.force_n.z(), -0.5 * force, 0.03 * force);
    // The haptic loop's totals are the same contact.
    SurfacePoints cloud(patch.points.size());
    cloud.count = patch.points.size();
    std::copy(patch.points.begin(), patch.points.end(), cloud.positions_mm.begin());
    std::copy(patch.normals.begin(), patch.normals.end(), cloud.normals.begin());
    std::copy(patch.areas.begin(), patch.areas.end(), cloud.areas_mm2.begin());
    cloud.triangles = patch.triangles;
    cloud.edges = surface_edges(patch.triangles);
    const ContactTotals totals = penalty_totals(between, parameters, cloud);
    EXPECT_NEAR((totals.force_on_tool_n - with.force_on_tool_n).norm(), 0.0, 1e-12);
    EXPECT_NEAR((totals.torque_on_tool_n_mm - with.torque_on_tool_n_mm).norm(), 0.0, 1e-12);
    EXPECT_NEAR(totals.pressure_pa, with.pressure_pa, 1e-9);
    EXPECT_NEAR(totals.stiffness_n_per_mm(2, 2), 9.0 * 5.0 / 100.0 * area, 1e-4 * 9.0 * 5.0 / 100.0 * area);
}

TEST_F(EdgePenalty, AnEdgeWithAnEndInsideIsLeftToThePointContact)
{
    // Centred on the column x = 0 the blade holds five vertices: they carry the contact, and the
    // edges from them are not pressed a second time.
    const ContactResult points_only = touch(at(0.0, 0.05), false);
    const ContactResult with = touch(at(0.0, 0.05), true);
    EXPECT_EQ(points_only.points.size(), 5u);
    EXPECT_EQ(with.points.size(), 5u);
    EXPECT_NEAR((with.force_on_tool_n - points_only.force_on_tool_n).norm(), 0.0, 1e-15);
}

TEST_F(EdgePenalty, AnEdgeTheBladeCrossedWithinTheStepPushesForThePartOfTheStepItWasIn)
{
    // Continuous, as a point: the blade comes down from 0.05 mm above to 0.05 mm below the patch
    // over the step, so each crossed edge is inside half of it, at a mean depth of 0.0125 mm.
    const PlacedShape from = at(1.0, -0.05);
    const ContactResult c = touch(at(1.0, 0.05), true, &from);
    const double area = 0.1 * 8.0 / 6.0;
    EXPECT_NEAR(-c.force_on_tool_n.z(), -9.0 * 5.0 / 100.0 * area * 0.0125, 1e-4 * 9.0 * 5.0 / 100.0 * area * 0.0125);
    // An edge's two ends share its stiffness, scaled by the half of the step it was inside.
    ASSERT_GE(c.points.size(), 2u);
    EXPECT_NEAR(c.points[0].stiffness_n_per_mm + c.points[1].stiffness_n_per_mm, 0.5 * 5.0 / 100.0 * area, 1e-4 * area);
}

TEST_F(EdgePenalty, AnEdgeLeftWithinTheStepPushesForThePartOfTheStepItWasIn)
{
    // Lifted fast: 0.05 mm in at the step's start, 5 mm clear at its end, so each crossed edge is
    // inside 0.05 / 5.05 of the step, at a mean depth of half 0.05 mm over that share.
    const PlacedShape from = at(1.0, 0.05);
    const ContactResult c = touch(at(1.0, -5.0), true, &from);
    const double area = 0.1 * 8.0 / 6.0, share = 0.05 / 5.05, expected = 9.0 * 5.0 / 100.0 * area * 0.5 * 0.05 * share;
    EXPECT_NEAR(-c.force_on_tool_n.z(), -expected, 1e-3 * expected);
}

namespace {

/// A wavy sheet of n x n points `spacing` mm apart, centred on the origin, each standing for
/// spacing^2 of area, triangulated and indexed (SurfacePoints::index: its grid of cells).
SurfacePoints wavy_sheet(int n, double spacing)
{
    SurfacePoints sheet(static_cast<std::size_t>(n * n));
    const double half = 0.5 * spacing * (n - 1);
    for (int j = 0; j < n; ++j)
        for (int i = 0; i < n; ++i) {
            const std::size_t k = static_cast<std::size_t>(j * n + i);
            const double x = spacing * i - half, y = spacing * j - half;
            sheet.positions_mm[k] = Vector3d(x, y, std::sin(0.3 * x) * std::cos(0.2 * y));
            sheet.normals[k] = Vector3d(-0.3 * std::cos(0.3 * x) * std::cos(0.2 * y), 0.2 * std::sin(0.3 * x) * std::sin(0.2 * y), 1.0).normalized();
            sheet.areas_mm2[k] = spacing * spacing;
        }
    sheet.count = sheet.capacity();
    for (int j = 0; j + 1 < n; ++j)
        for (int i = 0; i + 1 < n; ++i) {
            const int a = j * n + i;
            sheet.triangles.emplace_back(a, a + 1, a + n + 1);
            sheet.triangles.emplace_back(a, a + n + 1, a + n);
        }
    sheet.index();
    return sheet;
}

} // namespace

TEST(PenaltyTotals, TheSnapshotsGridVisitsEverythingThatTouches)
{
    // A wavy sheet of 0.7 mm triangles, indexed (SurfacePoints::index: its grid of cells), against
    // the same sheet without a grid (every point and edge visited): the same totals and the same
    // distances for the continuous check, for a blade and a ball at random poses, the blade's
    // edge often lying across faces between points (the edge penalty's case).
    const SurfacePoints sheet = wavy_sheet(44, 0.7);
    ASSERT_GT(sheet.grid.cell_mm, 0.0);
    SurfacePoints flat = sheet;
    flat.grid = PointGrid{};
    const ToolShape blade = ToolShape::box({8, 0.3, 4}), ball = ToolShape::sphere(2.0);
    std::srand(11);
    auto uniform = [](double lo, double hi) { return lo + (hi - lo) * std::rand() / static_cast<double>(RAND_MAX); };
    std::vector<double> d_grid(sheet.count), d_flat(sheet.count);
    int touched = 0;
    for (int trial = 0; trial < 40; ++trial) {
        const ToolShape& shape = trial % 2 ? ball : blade;
        const double height = trial % 2 ? 1.6 : 1.8;
        PlacedShape tool{&shape, Vector3d(uniform(-12, 12), uniform(-12, 12), height + uniform(-0.4, 0.2)),
                         Eigen::Quaterniond(Eigen::AngleAxisd(uniform(0, 3), Vector3d::UnitZ()))};
        const ContactParameters parameters{0.25, 5.0};
        const ContactTotals a = penalty_totals(tool, parameters, sheet, true, d_grid);
        const ContactTotals b = penalty_totals(tool, parameters, flat, true, d_flat);
        EXPECT_LT((a.force_on_tool_n - b.force_on_tool_n).norm(), 1e-12 * (1.0 + b.force_on_tool_n.norm())) << trial;
        EXPECT_LT((a.torque_on_tool_n_mm - b.torque_on_tool_n_mm).norm(), 1e-12 * (1.0 + b.torque_on_tool_n_mm.norm())) << trial;
        EXPECT_LT((a.stiffness_n_per_mm - b.stiffness_n_per_mm).norm(), 1e-12 * (1.0 + b.stiffness_n_per_mm.norm())) << trial;
        EXPECT_NEAR(a.area_mm2, b.area_mm2, 1e-12 * (1.0 + b.area_mm2)) << trial;
        EXPECT_NEAR(a.pressure_pa, b.pressure_pa, 1e-9 * (1.0 + b.pressure_pa)) << trial;
        for (std::size_t k = 0; k < sheet.count; ++k) ASSERT_EQ(d_grid[k], d_flat[k]) << trial << ", point " << k;
        // The same as the per-point model with the sheet's triangles (its edges included).
        const ContactResult list = penalty_contact(tool, parameters, std::span(sheet.positions_mm.data(), sheet.count),
                                                   std::span(sheet.areas_mm2.data(), sheet.count), std::span(sheet.normals.data(), sheet.count),
                                                   nullptr, sheet.triangles);
        EXPECT_LT((list.force_on_tool_n - a.force_on_tool_n).norm(), 1e-12 * (1.0 + a.force_on_tool_n.norm())) << trial;
        touched += b.area_mm2 > 0.0;
    }
    EXPECT_GT(touched, 20); // not vacuous: most poses touch the sheet
}

TEST(EdgePenaltySearch, AConvexToolsShortSearchFindsWhatTheGeneralSearchFindsOnTheSameShapeAsAMesh)
{
    // The same blade and scalpel twice: as themselves (their distance is convex along an edge,
    // searched by cutting planes and Newton steps) and as their own triangle meshes (searched by
    // halving, golden sections and bisections, which assume nothing). Random short edges around
    // them, tilted poses, a margin: the same edges pressed, with the same forces and torques to
    // the general search's own tolerance (0.1 um along the edge).
    std::srand(7);
    auto uniform = [](double lo, double hi) { return lo + (hi - lo) * std::rand() / RAND_MAX; };
    const ContactParameters parameters{0.25, 5.0};
    for (const ToolShape& convex : {ToolShape::box({16, 1, 8}), ToolShape::scalpel({2, 1.2, 8})}) {
        const ToolShape as_mesh = ToolShape::from_mesh(convex.mesh(0.0, 1));
        const Eigen::Quaterniond turn(Eigen::AngleAxisd(0.3, Vector3d(1, 2, 3).normalized()));
        const PlacedShape a{&convex, Vector3d(0.3, -0.2, 0.1), turn}, b{&as_mesh, a.position, turn};
        const Eigen::AlignedBox3d box = a.world_bounds(1.0);
        int pressed = 0;
        for (int trial = 0; trial < 400; ++trial) {
            const Vector3d p(uniform(box.min().x(), box.max().x()), uniform(box.min().y(), box.max().y()), uniform(box.min().z(), box.max().z()));
            const Vector3d q = p + Vector3d(uniform(-1.5, 1.5), uniform(-1.5, 1.5), uniform(-1.5, 1.5));
            const std::vector<Vector3d> points{p, q, p + Vector3d(0, 0, 50)}, normals(3, Vector3d(0, 0, 1));
            const std::vector<double> areas{1.0, 1.2, 1.0};
            const std::vector<Eigen::Vector3i> triangle{Eigen::Vector3i(0, 1, 2)};
            const ContactResult by_convex = penalty_contact(a, parameters, points, areas, normals, nullptr, triangle);
            const ContactResult by_mesh = penalty_contact(b, parameters, points, areas, normals, nullptr, triangle);
            ASSERT_EQ(by_convex.points.size(), by_mesh.points.size()) << "trial " << trial;
            const double scale = std::max(by_mesh.force_on_tool_n.norm(), 1e-9);
            EXPECT_NEAR((by_convex.force_on_tool_n - by_mesh.force_on_tool_n).norm(), 0.0, 1e-3 * scale) << "trial " << trial;
            EXPECT_NEAR((by_convex.torque_on_tool_n_mm - by_mesh.torque_on_tool_n_mm).norm(), 0.0, 2e-2 * scale) << "trial " << trial;
            const bool edge_only = by_mesh.points.size() == 2 && (points[0] - points[1]).norm() > 0.0 &&
                                   a.signed_distance(p) >= parameters.margin_mm && a.signed_distance(q) >= parameters.margin_mm;
            pressed += edge_only;
        }
        EXPECT_GT(pressed, 10); // the sample does press edges between their ends
    }
}

TEST(PenaltyTotals, LeavingOutWhatTheSnapshotsSlackAllowsChangesNothing)
{
    // A snapshot measured against a blade or a ball (measure_slack), then touched by the same tool
    // moved and turned a little, as the 1 kHz loop's ticks do between two snapshots, and moved
    // farther than most of the slack: the same totals, the same distances where both measured
    // them, and the same first contact of the continuous check, as the snapshot without slack.
    const SurfacePoints sheet = wavy_sheet(40, 0.6);
    const ToolShape blade = ToolShape::box({8, 0.3, 4}), ball = ToolShape::sphere(2.0);
    const ContactParameters parameters{0.25, 5.0};
    std::srand(5);
    auto uniform = [](double lo, double hi) { return lo + (hi - lo) * std::rand() / static_cast<double>(RAND_MAX); };
    std::vector<double> d_slack(sheet.count), d_all(sheet.count);
    int touched = 0, left_out = 0;
    for (int trial = 0; trial < 30; ++trial) {
        const ToolShape& shape = trial % 2 ? ball : blade;
        const PlacedShape measured{&shape, Vector3d(uniform(-8, 8), uniform(-8, 8), (trial % 2 ? 1.6 : 1.8) + uniform(-0.4, 0.1)),
                                   Eigen::Quaterniond(Eigen::AngleAxisd(uniform(0, 3), Vector3d(0.2, 0.1, 1).normalized()))};
        SurfacePoints with = sheet;
        measure_slack(measured, parameters.margin_mm, with);
        ASSERT_NEAR(with.slack_spent(measured, parameters.margin_mm), 0.0, 1e-12);
        EXPECT_EQ(with.slack_spent(measured, 0.5), INFINITY); // another margin: no slack
        for (int tick = 0; tick < 12; ++tick) {
            const double reach = tick < 8 ? 0.05 : 1.0; // a tick's drift, then farther
            PlacedShape tool = measured;
            tool.position += Vector3d(uniform(-reach, reach), uniform(-reach, reach), uniform(-reach, reach));
            tool.orientation = Eigen::Quaterniond(Eigen::AngleAxisd(uniform(-0.01, 0.01), Vector3d::UnitX())) * tool.orientation;
            const ContactTotals a = penalty_totals(tool, parameters, with, true, d_slack);
            const ContactTotals b = penalty_totals(tool, parameters, sheet, true, d_all);
            EXPECT_EQ(a.force_on_tool_n, b.force_on_tool_n) << trial << ", " << tick;
            EXPECT_EQ(a.torque_on_tool_n_mm, b.torque_on_tool_n_mm) << trial << ", " << tick;
            EXPECT_EQ(a.stiffness_n_per_mm, b.stiffness_n_per_mm) << trial << ", " << tick;
            EXPECT_EQ(a.area_mm2, b.area_mm2) << trial << ", " << tick;
            EXPECT_EQ(a.pressure_pa, b.pressure_pa) << trial << ", " << tick;
            for (std::size_t k = 0; k < sheet.count; ++k) {
                if (d_slack[k] < INFINITY) ASSERT_EQ(d_slack[k], d_all[k]) << trial << ", point " << k;
                left_out += d_slack[k] == INFINITY && d_all[k] < INFINITY;
            }
            PlacedShape to = tool;
            to.position += Vector3d(uniform(-0.3, 0.3), uniform(-0.3, 0.3), uniform(-0.6, 0.1));
            EXPECT_EQ(first_missed_contact(tool, to, parameters.margin_mm, with, {}, d_slack),
                      first_missed_contact(tool, to, parameters.margin_mm, sheet, {}, d_all))
                << trial << ", " << tick;
            touched += b.area_mm2 > 0.0;
        }
    }
    EXPECT_GT(touched, 100); // not vacuous: most ticks touch the sheet,
    EXPECT_GT(left_out, 10000); // and the slack does leave points out
}

TEST(PenaltyContact, ABladeBetweenTwoRowsOfPointsPressesOverNoMoreThanItsOwnShadow)
{
    // A blade 1 mm thick whose faces lie on two rows of points 1 mm apart, its edge 0.3 mm under
    // them: every point sits on a face, a margin deep, and carries the load. The two rows stand
    // for 30 mm^2, more than the blade itself covers seen from above (16 x 1 mm grown by the
    // margin: 16 + 2 x 17 x 0.25 + pi 0.25^2 mm^2), which is the area the pressure is taken over.
    const ToolShape blade = ToolShape::box({16, 1, 8});
    const ContactParameters parameters{0.25, 5.0};
    Patch rows(100.0); // its 10 x 10 grid far away: only the rows below are near
    for (int i = -7; i <= 7; ++i)
        for (const double y : {-0.5, 0.5}) rows.add(Vector3d(i, y, 0.0), Vector3d(0, 0, 1), 1.0);
    const PlacedShape pressed{&blade, Vector3d(0, 0, 4.0 - 0.3), Eigen::Quaterniond::Identity()};
    const ContactResult c = rows.contact(pressed, parameters);
    ASSERT_EQ(c.points.size(), 30u);
    const double force = 30 * 5.0 / 100.0 * 1.0 * 0.25, shadow = 16.0 + 2.0 * 17.0 * 0.25 + M_PI * 0.0625;
    EXPECT_NEAR(-c.force_on_tool_n.z(), -force, 1e-12);
    EXPECT_NEAR(c.area_mm2, 30.0, 1e-12);
    EXPECT_NEAR(c.load_area_mm2, shadow, 1e-9);
    EXPECT_NEAR(c.pressure_pa, 1e6 * force / shadow, 1e-6); // 15.2 kPa, not the rows' 12.5 kPa
    // A broad plate over the same rows: its shadow is larger, the rows' own area stands.
    const ContactResult broad = rows.contact(plate_pressing(0.25, parameters), parameters);
    EXPECT_NEAR(broad.load_area_mm2, 30.0, 1e-12);
}
