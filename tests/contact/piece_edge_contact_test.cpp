// The edge-under-edge narrow phase against cases worked by hand: two ridges pressed across each
// other (no vertex of either in the other, so only an edge contact sees it) give one contact at
// the ridges' crossing with k d a, a the share of the edge in times a sixth of its ends' areas;
// apart they give none, arriving they are caught with no push yet, crossed at rest by more than
// the tolerance they are the far side of the material; a closed shape alone and two flat faces
// pressed together have no edge under an edge.

#include "contact/piece_contact.hpp"

#include <Eigen/Geometry>
#include <gtest/gtest.h>

#include <cmath>

namespace vox::contact {
namespace {

PieceContactParameters parameters()
{
    PieceContactParameters k;
    k.stiffness_n_per_mm = 10.0;
    k.max_depth_mm = 1.0;
    k.rest_tolerance_mm = 0.5;
    k.skin_mm = 0.02;
    return k;
}

/// Adds a closed triangular prism, 10 mm long, its ridge pointing up (`up`) or down: the ridge
/// along x (`along_x`) or y through `ridge` (now) and `ridge_rest` (at rest), its base 1 mm from
/// the ridge and 2 mm wide. Triangles are turned to face out from the prism's centre.
void add_prism(SurfacePatch& p, bool along_x, bool up, const Eigen::Vector3d& ridge, const Eigen::Vector3d& ridge_rest)
{
    const int base = static_cast<int>(p.start_mm.size());
    const Eigen::Vector3d axis = along_x ? Eigen::Vector3d::UnitX() : Eigen::Vector3d::UnitY();
    const Eigen::Vector3d across = along_x ? Eigen::Vector3d::UnitY() : Eigen::Vector3d::UnitX();
    const Eigen::Vector3d down(0.0, 0.0, up ? -1.0 : 1.0);
    // 0, 1: the ridge's ends; 2, 3 and 4, 5: the base's two long sides.
    const Eigen::Vector3d offsets[6] = {-5 * axis, 5 * axis, -5 * axis + down - across, 5 * axis + down - across, -5 * axis + down + across,
                                        5 * axis + down + across};
    for (const Eigen::Vector3d& o : offsets) {
        p.start_mm.push_back(ridge + o);
        p.end_mm.push_back(ridge + o);
        p.rest_mm.push_back(ridge_rest + o);
        p.presses.push_back(1);
    }
    const int faces[8][3] = {{0, 1, 3}, {0, 3, 2}, {0, 4, 5}, {0, 5, 1}, {2, 3, 5}, {2, 5, 4}, {0, 2, 4}, {1, 5, 3}};
    const Eigen::Vector3d centre = ridge + (2.0 / 3.0) * down;
    for (const auto& f : faces) {
        Eigen::Vector3i t(base + f[0], base + f[1], base + f[2]);
        auto at = [&](int c) { return p.start_mm[static_cast<std::size_t>(t[c])]; };
        if ((at(1) - at(0)).cross(at(2) - at(0)).dot((at(0) + at(1) + at(2)) / 3.0 - centre) < 0.0) std::swap(t[1], t[2]);
        p.triangles.push_back(t);
    }
}

/// A third of the areas of the triangles around vertex v (at the start).
double vertex_area(const SurfacePatch& p, int v)
{
    double a = 0.0;
    for (const Eigen::Vector3i& t : p.triangles)
        if ((t.array() == v).any()) {
            auto at = [&](int c) { return p.start_mm[static_cast<std::size_t>(t[c])]; };
            a += (at(1) - at(0)).cross(at(2) - at(0)).norm() / 6.0;
        }
    return a;
}

/// A prism with its ridge up along x at z = 1, and one with its ridge down along y, `gap` above it
/// (negative: pressed in), both at rest `rest_gap` apart.
SurfacePatch crossed_ridges(double gap, double rest_gap)
{
    SurfacePatch p;
    add_prism(p, true, true, {0, 0, 1}, {0, 0, 1});
    add_prism(p, false, false, {0, 0, 1 + gap}, {0, 0, 1 + rest_gap});
    return p;
}

TEST(PieceEdgeContact, TwoRidgesPressedAcrossEachOtherGiveOneContactWithStiffnessTimesDepthTimesArea)
{
    const SurfacePatch p = crossed_ridges(-0.1, 0.0);
    // No vertex of either prism is in the other: the vertex-face phase sees nothing.
    EXPECT_TRUE(face_contacts(p, parameters()).empty());
    const std::vector<EdgeContact> c = edge_contacts(p, parameters());
    ASSERT_EQ(c.size(), 1u); // each ridge is under the other: one contact for the pair
    const EdgeContact& e = c[0];
    EXPECT_NEAR(e.depth_mm, 0.1, 1e-12);
    EXPECT_NEAR(std::abs(e.normal.z()), 1.0, 1e-12);
    EXPECT_NEAR(e.s, 0.5, 1e-12);
    EXPECT_NEAR(e.t, 0.5, 1e-12);
    // The pressing ridge's point is pushed out of the other prism: the lower ridge down, the upper up.
    const bool lower_presses = e.edge[0] < 6;
    EXPECT_EQ(e.normal.z() < 0.0, lower_presses);
    EXPECT_EQ(e.pressed[0] < 6, !lower_presses);
    // The other prism is 0.1 mm wide each side of its ridge 0.1 mm above it: 0.2 mm of the 10 mm ridge in.
    const double area = 0.02 * (vertex_area(p, static_cast<int>(e.edge[0])) + vertex_area(p, static_cast<int>(e.edge[1]))) / 6.0;
    EXPECT_NEAR(e.area_mm2, area, 1e-9);
    EXPECT_NEAR(e.stiffness_n_per_mm, 0.1 * area, 1e-12); // 10 N/mm per cm^2
    EXPECT_NEAR(e.force_n, 0.1 * area * 0.1, 1e-12);
}

TEST(PieceEdgeContact, RidgesApartAreNoContactAndOnesAboutToCrossAreCaughtWithNoPushYet)
{
    SurfacePatch p = crossed_ridges(0.3, 0.3);
    EXPECT_TRUE(edge_contacts(p, parameters()).empty());
    for (std::size_t v = 6; v < 12; ++v) p.end_mm[v].z() -= 0.5; // predicted 0.2 mm in at the step's end
    const std::vector<EdgeContact> c = edge_contacts(p, parameters());
    ASSERT_EQ(c.size(), 1u);
    EXPECT_NEAR(c[0].depth_mm, -0.3, 1e-12);
    EXPECT_LT(c[0].force_n, 0.0);
    EXPECT_GT(c[0].stiffness_n_per_mm, 0.0);
}

TEST(PieceEdgeContact, RidgesCrossedAtRestByMoreThanTheToleranceAreTheFarSideOfTheMaterial)
{
    EXPECT_EQ(edge_contacts(crossed_ridges(-0.1, -0.4), parameters()).size(), 1u); // within the tolerance: a contact
    EXPECT_TRUE(edge_contacts(crossed_ridges(-0.1, -0.6), parameters()).empty());
    EXPECT_TRUE(edge_contacts(crossed_ridges(-1.2, 0.0), parameters()).empty()); // deeper than max_depth: gone through
}

TEST(PieceEdgeContact, AClosedShapeAloneAndTwoFlatFacesPressedTogetherHaveNoEdgeUnderAnEdge)
{
    SurfacePatch one;
    add_prism(one, true, true, {0, 0, 1}, {0, 0, 1});
    EXPECT_TRUE(edge_contacts(one, parameters()).empty());
    // Two prisms' flat bases pressed 0.1 mm into each other: the vertices press, no edge passes under one.
    SurfacePatch flat;
    add_prism(flat, true, true, {0, 0, 1}, {0, 0, 1});   // base at z = 0, facing down
    add_prism(flat, true, false, {0, 0, -0.9}, {0, 0, -1}); // base at z = 0.1, facing up
    EXPECT_FALSE(face_contacts(flat, parameters()).empty());
    EXPECT_TRUE(edge_contacts(flat, parameters()).empty());
}

TEST(PieceEdgeContact, MismatchedArraysAreRefused)
{
    SurfacePatch p = crossed_ridges(-0.1, 0.0);
    p.rest_mm.pop_back();
    EXPECT_THROW(static_cast<void>(edge_contacts(p, parameters())), std::invalid_argument);
}

} // namespace
} // namespace vox::contact
