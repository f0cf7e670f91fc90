// The narrow phase of the object's contact with itself, against cases worked by hand: two flat
// faces pressed together are pushed apart with k d A, half from each side's vertices; the far side
// of a thin plate (through material at rest), a face that does not face the vertex and a
// triangle's own corners are no contacts; a vertex about to arrive is caught with no force yet.

#include "contact/piece_contact.hpp"

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

} // namespace
} // namespace vox::contact
