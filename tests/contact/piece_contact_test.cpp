// The narrow phase of the object's contact with itself, against cases worked by hand: two flat
// faces pressed together are pushed apart with k d A, half from each side's vertices; the far side
// of a thin plate (through material at rest), a face that does not face the vertex and a
// triangle's own corners are no contacts; a vertex about to arrive is caught with no force yet.
// Edge under edge: two ridges pressed across each other (no vertex of either in the other, so only
// an edge contact sees it) give one contact at the ridges' crossing with k d a, a the share of the
// edge in times a sixth of its ends' areas; apart they give none, arriving they are caught with no
// push yet, crossed at rest by more than the tolerance they are the far side of the material; a
// closed shape alone and two flat faces pressed together have no edge under an edge.

#include "contact/piece_contact.hpp"

#include <Eigen/Geometry>
#include <cmath>
#include <gtest/gtest.h>

namespace vox::contact {
namespace {

/// Adds an n x n grid of unit squares (two triangles each) in the plane z = z_rest at rest, moved
/// to z = z_now, facing +z (`up`) or -z.
void add_sheet(SurfacePatch& p, int n, double z_rest, double z_now, bool up)
{
    const int base = static_cast<int>(p.start_mm.size());
    for (int j = 0; j <= n; ++j)
        for (int i = 0; i <= n; ++i) {
            p.rest_mm.emplace_back(i, j, z_rest);
            p.start_mm.emplace_back(i, j, z_now);
            p.end_mm.emplace_back(i, j, z_now);
            p.presses.push_back(1);
        }
    auto at = [&](int i, int j) { return base + j * (n + 1) + i; };
    for (int j = 0; j < n; ++j)
        for (int i = 0; i < n; ++i) {
            Eigen::Vector3i a(at(i, j), at(i + 1, j), at(i + 1, j + 1)), b(at(i, j), at(i + 1, j + 1), at(i, j + 1));
            if (!up) {
                std::swap(a[1], a[2]);
                std::swap(b[1], b[2]);
            }
            p.triangles.push_back(a);
            p.triangles.push_back(b);
        }
}

PieceContactParameters parameters()
{
    PieceContactParameters k;
    k.stiffness_n_per_mm = 10.0;
    k.max_depth_mm = 1.0;
    k.rest_tolerance_mm = 0.5;
    k.skin_mm = 0.02;
    return k;
}

TEST(PieceContact, TwoFlatFacesPressedTogetherArePushedApartWithStiffnessTimesDepthTimesArea)
{
    // A lower piece's top (facing up) at rest at z = 0, an upper piece's bottom (facing down) at
    // rest at z = 1, pressed 0.1 mm into each other. Interior vertices carry 1 mm^2, edge ones less.
    SurfacePatch p;
    add_sheet(p, 10, 0.0, 0.05, true);
    add_sheet(p, 10, 1.0, -0.05, false);
    const std::vector<FaceContact> c = face_contacts(p, parameters());
    double up = 0.0, down = 0.0;
    for (const FaceContact& f : c) {
        EXPECT_NEAR(f.depth_mm, 0.1, 1e-12);
        EXPECT_NEAR(std::abs(f.normal.z()), 1.0, 1e-12);
        (f.normal.z() > 0.0 ? up : down) += f.force_n; // on the vertex, along the pressed face's normal
    }
    // Each side's vertices press the other's faces over the whole 10 x 10 mm^2, at half their area:
    // k d A / 2 = 0.1 N/mm^2 x 0.1 mm x 100 mm^2 / 2 each way, the two halves making k d A.
    EXPECT_EQ(c.size(), 2u * 121u);
    EXPECT_NEAR(up, 0.5, 1e-9);
    EXPECT_NEAR(down, 0.5, 1e-9);
}

TEST(PieceContact, TheFarSideOfAThinPlateIsNoContact)
{
    // One plate 0.6 mm thick: its bottom at rest lies behind its top by more than the tolerance.
    // Squeezed to 0.05 mm apart and then flipped through by 0.05 mm it is still one plate.
    SurfacePatch p;
    add_sheet(p, 4, 0.6, 0.0, true);   // top, facing up, moved down
    add_sheet(p, 4, 0.0, 0.05, false); // bottom, facing down, moved up: behind the top by 0.05 mm
    EXPECT_TRUE(face_contacts(p, parameters()).empty());
}

TEST(PieceContact, FacesThatDoNotFaceEachOtherAndAVertexsOwnTrianglesAreNoContact)
{
    // Two sheets facing the same way, one 0.1 mm behind the other: not facing.
    SurfacePatch p;
    add_sheet(p, 3, 0.0, 0.0, true);
    add_sheet(p, 3, 1.0, -0.1, true);
    EXPECT_TRUE(face_contacts(p, parameters()).empty());
    // One sheet alone: every vertex lies on its own triangles.
    SurfacePatch q;
    add_sheet(q, 3, 0.0, 0.0, true);
    EXPECT_TRUE(face_contacts(q, parameters()).empty());
}

TEST(PieceContact, AVertexAboutToArriveIsCaughtWithNoPushYetAndOneFarAwayIsNot)
{
    SurfacePatch p;
    add_sheet(p, 4, 0.0, 0.0, true);
    add_sheet(p, 4, 1.0, 0.5, false); // 0.5 mm above the lower sheet
    EXPECT_TRUE(face_contacts(p, parameters()).empty());
    for (std::size_t v = 25; v < p.end_mm.size(); ++v) p.end_mm[v].z() = -0.1; // predicted to pass it within the step
    const std::vector<FaceContact> c = face_contacts(p, parameters());
    ASSERT_EQ(c.size(), 50u); // each side's 25 vertices against the other's faces
    for (const FaceContact& f : c) {
        EXPECT_NEAR(f.depth_mm, -0.5, 1e-12); // apart at the start: the solve pulls it no further than the face
        EXPECT_LT(f.force_n, 0.0);
        EXPECT_GT(f.stiffness_n_per_mm, 0.0);
    }
}

TEST(PieceContact, MismatchedArraysAreRefused)
{
    SurfacePatch p;
    add_sheet(p, 2, 0.0, 0.0, true);
    p.presses.pop_back();
    EXPECT_THROW(static_cast<void>(face_contacts(p, parameters())), std::invalid_argument);
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
