// A blade's swept surface as a cut: Möller's test finds the edges its patches meet (through a
// triangle, across the seam between two, not beside or along them); its level is the signed
// distance from the nearest patch's plane; a half circle of patches unrolls flat; a model cut along patches in one plane cuts exactly as
// along the plane within their region; and along a bent sweep each tetrahedron's crack meets its
// neighbours' on their shared edges, with no tetrahedron cut twice.

#include "isxfem/xfem_model.hpp"

#include "isxfem/arc_sweep.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <map>

using namespace vox::isxfem;

namespace {

/// The square [y0, y1] x [z0, z1] in the plane x = `x`, facing +x.
CutPatch square_at_x(double x, double y0, double y1, double z0, double z1)
{
    CutPatch p;
    p.corners = {{x, y0, z0}, {x, y1, z0}, {x, y1, z1}, {x, y0, z1}};
    p.normal = Eigen::Vector3d::UnitX();
    return p;
}

XfemModel lattice_model()
{
    return {cube_lattice({6, 4, 4}, 1.0), {vox::grid::ElasticMaterial{vox::grid::lame_from_young_poisson(1e5, 0.3), 1000.0}}, std::vector<std::uint32_t>(6 * 96, 0), 0.1};
}

} // namespace

TEST(CutSurface, MollersTestFindsTheSegmentsThatMeetAPatch)
{
    CutSurface s;
    s.add(square_at_x(1.0, 0.0, 2.0, 0.0, 1.0));
    EXPECT_TRUE(s.meets({0.5, 1.5, 0.2}, {1.5, 1.5, 0.2}));   // through one triangle
    EXPECT_TRUE(s.meets({0.5, 1.0, 0.5}, {1.5, 1.0, 0.5}));   // through the seam of the two (the square's diagonal)
    EXPECT_TRUE(s.meets({1.5, 0.3, 0.3}, {0.5, 0.3, 0.3}));   // either way along it
    EXPECT_FALSE(s.meets({0.5, 2.5, 0.5}, {1.5, 2.5, 0.5}));  // beside it
    EXPECT_FALSE(s.meets({0.5, 1.0, 0.5}, {0.9, 1.0, 0.5}));  // short of it
    EXPECT_FALSE(s.meets({1.0, 0.5, 0.5}, {1.0, 1.5, 0.5}));  // along its plane
    const CutSurface plane(PlaneCut{Eigen::Vector3d::UnitX(), 1.0});
    EXPECT_TRUE(plane.meets({0.5, 9.0, 9.0}, {1.5, 9.0, 9.0})); // a plane reaches everywhere
}

TEST(CutSurface, ItsLevelIsTheSignedDistanceFromTheNearestPatchsPlane)
{
    // A sheet folded along z = 1: x = 1 below, turning by 30 degrees about the fold above.
    CutSurface s;
    s.add(square_at_x(1.0, 0.0, 2.0, 0.0, 1.0));
    const double c = std::cos(M_PI / 6.0), t = std::sin(M_PI / 6.0);
    CutPatch upper;
    upper.normal = Eigen::Vector3d(c, 0.0, -t);
    upper.corners = {{1.0, 0.0, 1.0}, {1.0, 2.0, 1.0}, {1.0 + t, 2.0, 1.0 + c}, {1.0 + t, 0.0, 1.0 + c}};
    s.add(upper);
    EXPECT_NEAR(s.level({0.7, 1.0, 0.5}), -0.3, 1e-12);
    EXPECT_NEAR(s.level({1.2, 1.0, 0.2}), 0.2, 1e-12);
    const Eigen::Vector3d above = Eigen::Vector3d(1.0 + 0.5 * t, 1.0, 1.0 + 0.5 * c) + 0.25 * upper.normal;
    EXPECT_NEAR(s.level(above), 0.25, 1e-12);
    EXPECT_NEAR((s.normal(above) - upper.normal).norm(), 0.0, 1e-12);
    EXPECT_NEAR(s.bounds(1).min().z(), 1.0, 1e-12);
}

TEST(CutSurface, AHalfCircleSweepUnrollsFlatWithoutFolding)
{
    // 36 patches of 5 degrees round a half circle of radius 2 about the z axis, 1 high, half of
    // them given clockwise (add() turns them): unrolled, the arc becomes a straight strip as long
    // as the arc, its height the other axis, the same way up all along.
    const double radius = 2.0, step = M_PI / 36.0;
    CutSurface s;
    auto on_arc = [&](double angle, double z) { return Eigen::Vector3d(radius * std::cos(angle), radius * std::sin(angle), z); };
    for (int k = 0; k < 36; ++k) {
        CutPatch p;
        p.corners = {on_arc(k * step, 0.0), on_arc((k + 1) * step, 0.0), on_arc((k + 1) * step, 1.0), on_arc(k * step, 1.0)};
        if (k % 2) std::reverse(p.corners.begin(), p.corners.end());
        const double middle = (k + 0.5) * step;
        p.normal = -Eigen::Vector3d(std::cos(middle), std::sin(middle), 0.0); // towards the centre
        s.add(p);
    }
    for (const CutPatch& p : s.patches()) // counter-clockwise seen from +normal, each
        EXPECT_GT((p.corners[1] - p.corners[0]).cross(p.corners[2] - p.corners[0]).dot(p.normal), 0.0);
    const Eigen::Vector2d start = s.unrolled(on_arc(0.01, 0.5)), up = s.unrolled(on_arc(0.01, 0.9)) - start;
    for (double angle = 0.3; angle < M_PI - 0.05; angle += 0.3) {
        const Eigen::Vector2d here = s.unrolled(on_arc(angle, 0.5));
        EXPECT_NEAR((here - start).norm(), radius * (angle - 0.01), 0.01 * radius * angle) << angle; // a chord's sagitta aside
        EXPECT_NEAR((here - start).dot(up), 0.0, 1e-3) << angle;                                      // straight
        EXPECT_NEAR(((s.unrolled(on_arc(angle, 0.9)) - here) - up).norm(), 0.0, 1e-9) << angle;      // the same way up
    }
    // Over a patch and near its plane; too far off it; beyond the sweep's end.
    EXPECT_TRUE(s.covers(0.95 * on_arc(1.0, 0.5), 0.15));
    EXPECT_FALSE(s.covers(0.95 * on_arc(1.0, 0.5), 0.05));
    EXPECT_FALSE(s.covers(on_arc(-0.2, 0.5), 0.15));
}

TEST(CutSurface, PatchesInOnePlaneCutAsThePlaneWithinTheirRegion)
{
    // A blade's frames across x = 3.1 covering y < 2.5, overlapping as a stroke's do. (The partly
    // crossed tetrahedra differ: the sweep only looks near its patches, the plane everywhere.)
    CutSurface sweep;
    for (double y = -0.5; y < 2.5; y += 0.4) sweep.add(square_at_x(3.1, y, std::min(y + 0.6, 2.5), -1.0, 5.0));
    XfemModel swept = lattice_model(), planar = lattice_model();
    const CutReport a = swept.cut(sweep, 0);
    const CutReport b = planar.cut(PlaneCut{Eigen::Vector3d::UnitX(), 3.1}, [](const Eigen::Vector3d& p) { return p.y() <= 2.5; });
    EXPECT_GT(a.cut_tets, 0u);
    EXPECT_EQ(a.cut_tets, b.cut_tets);
    EXPECT_EQ(a.new_blocks, b.new_blocks);
    for (std::size_t t = 0; t < swept.elements().size(); ++t) {
        ASSERT_EQ(swept.elements()[t].cuts.size(), planar.elements()[t].cuts.size()) << t;
        for (std::size_t c = 0; c < swept.elements()[t].cuts.size(); ++c)
            for (std::size_t n = 0; n < 4; ++n) EXPECT_NEAR(swept.elements()[t].cuts[c].phi[n], planar.elements()[t].cuts[c].phi[n], 1e-12);
    }
}

TEST(CutSurface, ABentSweepCutsEachTetrahedronOnceAndItsCracksMeet)
{
    // A blade turning by 80 degrees about the vertical as it crosses the lattice, in frames of 2
    // degrees, each a flat patch: one cut through, no tetrahedron cut twice or left partly cut, and
    // where two cut tetrahedra share an edge the crack crosses it at the same point in both.
    const Eigen::Vector2d centre(7.1, 2.0);
    const double radius = 4.0;
    const CutSurface sweep = vox::test::arc_sweep(centre, radius, -40.0 * M_PI / 180.0, 40.0 * M_PI / 180.0, 2.0 * M_PI / 180.0);
    XfemModel model = lattice_model();
    const CutReport r = model.cut(sweep, 0);
    EXPECT_EQ(r.cut, 0);
    EXPECT_EQ(r.recut_tets, 0u);
    EXPECT_EQ(r.partial_tets, 0u);
    EXPECT_GE(r.cut_tets, 4u * 4u * 6u); // a layer of cubes across the 4 x 4 section, at least
    std::map<std::pair<std::uint32_t, std::uint32_t>, Eigen::Vector3d> crossing;
    int shared = 0;
    for (const XfemElement& e : model.elements()) {
        if (!e.is_cut()) continue;
        const ElementCut& c = e.cuts[0];
        for (std::size_t a = 0; a < 4; ++a)
            for (std::size_t b = a + 1; b < 4; ++b) {
                if ((c.phi[a] < 0.0) == (c.phi[b] < 0.0)) continue;
                const Eigen::Vector3d& xa = model.mesh().nodes[e.node[a]];
                const Eigen::Vector3d& xb = model.mesh().nodes[e.node[b]];
                const Eigen::Vector3d x = xa + c.phi[a] / (c.phi[a] - c.phi[b]) * (xb - xa);
                // On the bend, to within the sagitta of a tetrahedron edge's chord (1.7^2 / 8 r).
                EXPECT_LT(std::abs((x.head<2>() - centre).norm() - radius), 0.1);
                const auto [it, fresh] = crossing.try_emplace(std::minmax(e.node[a], e.node[b]), x);
                if (!fresh) {
                    EXPECT_LT((it->second - x).norm(), 1e-12);
                    ++shared;
                }
            }
    }
    EXPECT_GT(shared, 0);
}
