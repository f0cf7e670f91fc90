// Closing an embedded surface along a cut: a box's surface, finer than the tetrahedra it is
// embedded in, cut through and slit halfway down, by planes and by a blade's sweep that bends.
// Checked against what the geometry must give: a closed, consistently oriented surface (every
// edge used once each way), the crack faces' area (S and R intersected, computed by hand), the
// enclosed volume unchanged at rest, and the right number of pieces.

#include "isxfem/cut_closure.hpp"

#include "core/union_find.hpp"
#include "isxfem/arc_sweep.hpp"

#include <Eigen/Geometry>
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <functional>
#include <map>
#include <memory>
#include <set>

using namespace vox::isxfem;

namespace {

/// The surface of the box [lo, hi], each face a grid of squares of about `step` split in two,
/// outward, vertices shared along the edges.
void box_surface(const Eigen::Vector3d& lo, const Eigen::Vector3d& hi, double step, std::vector<Eigen::Vector3d>& x,
                 std::vector<Eigen::Vector3i>& triangles)
{
    std::map<std::array<long, 3>, int> index;
    auto vertex = [&](const Eigen::Vector3d& p) {
        const std::array<long, 3> key{std::lround(p.x() * 1e6), std::lround(p.y() * 1e6), std::lround(p.z() * 1e6)};
        const auto [it, fresh] = index.try_emplace(key, static_cast<int>(x.size()));
        if (fresh) x.push_back(p);
        return it->second;
    };
    for (int axis = 0; axis < 3; ++axis)
        for (int end = 0; end < 2; ++end) {
            const int a = (axis + 1) % 3, b = (axis + 2) % 3;
            const int na = static_cast<int>(std::ceil((hi[a] - lo[a]) / step)), nb = static_cast<int>(std::ceil((hi[b] - lo[b]) / step));
            auto at = [&](int i, int j) {
                Eigen::Vector3d p;
                p[axis] = end ? hi[axis] : lo[axis];
                p[a] = lo[a] + (hi[a] - lo[a]) * i / na;
                p[b] = lo[b] + (hi[b] - lo[b]) * j / nb;
                return vertex(p);
            };
            for (int i = 0; i < na; ++i)
                for (int j = 0; j < nb; ++j) {
                    const int p00 = at(i, j), p10 = at(i + 1, j), p01 = at(i, j + 1), p11 = at(i + 1, j + 1);
                    // (a, b, axis) is right-handed: counter-clockwise in (a, b) faces +axis.
                    if (end) {
                        triangles.emplace_back(p00, p10, p11);
                        triangles.emplace_back(p00, p11, p01);
                    } else {
                        triangles.emplace_back(p00, p11, p10);
                        triangles.emplace_back(p00, p01, p11);
                    }
                }
        }
}

struct Closed {
    std::shared_ptr<XfemModel> model;
    std::vector<SurfacePoint> points;
    std::vector<Eigen::Vector3i> triangles;
    ClosureCounts counts;
};

/// A 6 x 4 x 4 lattice of 1 m cubes with the box surface [0.05, 5.95] x [0.05, 3.95]^2 embedded
/// (triangles of about `step`; with `cavity`, a void inside it too), cut by `cuts` (their reports
/// in order), then closed along each cut.
Closed closed_box(const std::function<std::vector<CutReport>(XfemModel&)>& cuts, double step = 0.39, bool cavity = false)
{
    Closed out;
    out.model = std::make_shared<XfemModel>(cube_lattice({6, 4, 4}, 1.0), std::vector<vox::grid::ElasticMaterial>{vox::grid::ElasticMaterial{vox::grid::lame_from_young_poisson(1e5, 0.3), 1000.0}},
                                            std::vector<std::uint32_t>(6 * 96, 0), 0.1);
    XfemModel& model = *out.model;
    std::vector<Eigen::Vector3d> x;
    box_surface({0.05, 0.05, 0.05}, {5.95, 3.95, 3.95}, step, x, out.triangles);
    if (cavity) { // a void [2.5, 3.7] x [1.3, 2.7]^2 inside: its surface faces into it
        std::vector<Eigen::Vector3i> inner;
        const auto first = static_cast<int>(x.size());
        std::vector<Eigen::Vector3d> inner_x;
        box_surface({2.5, 1.3, 1.3}, {3.7, 2.7, 2.7}, 0.3, inner_x, inner);
        x.insert(x.end(), inner_x.begin(), inner_x.end());
        for (const Eigen::Vector3i& t : inner) out.triangles.emplace_back(t[0] + first, t[2] + first, t[1] + first);
    }
    const auto neighbours = face_neighbours(model.mesh());
    const std::vector<CutReport> reports = cuts(model);
    const CutClosure closure(model);
    for (const Eigen::Vector3d& p : x) {
        const auto [tet, bary] = walk_to(model.mesh(), neighbours, 0, p);
        out.points.push_back({tet, bary, static_cast<int>(model.elements()[tet].region_at(bary)), p, 0});
    }
    for (const CutReport& r : reports) out.counts += closure.close(r.cut, out.points, out.triangles);
    return out;
}

/// The box cut by the plane x = 3.1 where `inside` holds, and then by `second` where
/// `second_inside` does (crossing the first). With the default step the surface's vertices lie on
/// y = 2 and z = 2, where the cubes' faces are: the crack's front runs along the surface's edges
/// and meets the surface at its vertices.
Closed cut_box(const std::function<bool(const Eigen::Vector3d&)>& inside, double step = 0.39, bool cavity = false,
               const PlaneCut* second = nullptr, const std::function<bool(const Eigen::Vector3d&)>& second_inside = {})
{
    return closed_box(
        [&](XfemModel& model) {
            std::vector<CutReport> reports{model.cut(PlaneCut{Eigen::Vector3d::UnitX(), 3.1}, inside)};
            EXPECT_GT(reports[0].cut_tets, 0u);
            if (second) {
                reports.push_back(model.cut(*second, second_inside));
                EXPECT_GT(reports[1].crossed_tets, 0u);
            }
            return reports;
        },
        step, cavity);
}

/// Every edge used once in each direction: closed and consistently oriented.
void expect_closed(const Closed& c)
{
    std::map<std::pair<int, int>, int> uses;
    for (const Eigen::Vector3i& t : c.triangles)
        for (int k = 0; k < 3; ++k) ++uses[{t[k], t[(k + 1) % 3]}];
    int once_each_way = 0, wrong = 0;
    for (const auto& [edge, n] : uses) {
        const auto back = uses.find({edge.second, edge.first});
        if (n == 1 && back != uses.end() && back->second == 1)
            ++once_each_way;
        else
            ++wrong;
    }
    EXPECT_EQ(wrong, 0) << "edges not used exactly once each way, of " << uses.size();
    EXPECT_GT(once_each_way, 0);
}

/// Volume enclosed (divergence theorem) and area of the triangles lying in the plane x = 3.1 (or
/// y = `y` when given).
std::pair<double, double> volume_and_crack_area(const Closed& c, double y = NAN)
{
    double volume = 0.0, crack = 0.0;
    for (const Eigen::Vector3i& t : c.triangles) {
        const Eigen::Vector3d& a = c.points[static_cast<std::size_t>(t[0])].rest_m;
        const Eigen::Vector3d& b = c.points[static_cast<std::size_t>(t[1])].rest_m;
        const Eigen::Vector3d& d = c.points[static_cast<std::size_t>(t[2])].rest_m;
        volume += a.dot(b.cross(d)) / 6.0;
        const bool on_x = std::abs(a.x() - 3.1) < 1e-9 && std::abs(b.x() - 3.1) < 1e-9 && std::abs(d.x() - 3.1) < 1e-9;
        const bool on_y = std::abs(a.y() - y) < 1e-9 && std::abs(b.y() - y) < 1e-9 && std::abs(d.y() - y) < 1e-9;
        if (std::isnan(y) ? on_x : on_y) crack += 0.5 * (b - a).cross(d - a).norm();
    }
    return {volume, crack};
}

/// The surface's points joined by its triangles.
vox::UnionFind joined(const Closed& c)
{
    vox::UnionFind sets(c.points.size());
    for (const Eigen::Vector3i& t : c.triangles)
        for (int k = 1; k < 3; ++k) sets.unite(static_cast<std::uint32_t>(t[0]), static_cast<std::uint32_t>(t[k]));
    return sets;
}

/// Every piece of the surface lies on one side of each cut through the object (all cuts, or
/// `through`): where a point's tetrahedron was cut, its region says which; elsewhere its rest
/// position (off the plane) does.
void expect_pieces_on_one_side(const Closed& c, std::vector<int> through = {})
{
    if (through.empty())
        for (int cut = 0; cut < c.model->cut_count(); ++cut) through.push_back(cut);
    vox::UnionFind pieces = joined(c);
    auto root = [&](int i) { return static_cast<int>(pieces.find(static_cast<std::uint32_t>(i))); };
    for (const int cut : through) {
        std::map<int, int> side_of_piece;
        int disagreements = 0;
        for (std::size_t i = 0; i < c.points.size(); ++i) {
            const SurfacePoint& p = c.points[i];
            const XfemElement& el = c.model->elements()[p.tet];
            const int at = el.cut_index(cut);
            int side = -1;
            if (at >= 0)
                side = (p.side >> at) & 1;
            else if (std::abs(c.model->cut_surface(cut).level(p.rest_m)) > 1e-9)
                side = c.model->cut_surface(cut).level(p.rest_m) > 0.0;
            if (side < 0) continue;
            const auto [it, fresh] = side_of_piece.try_emplace(root(static_cast<int>(i)), side);
            if (!fresh && it->second != side) ++disagreements;
        }
        EXPECT_EQ(disagreements, 0) << "cut " << cut;
    }
}

/// Connected pieces when the two sides of the crack are told apart (a vertex on the crack is one
/// per side, so a through-cut leaves two).
int pieces(const Closed& c)
{
    vox::UnionFind sets = joined(c);
    std::set<std::uint32_t> roots;
    for (const Eigen::Vector3i& t : c.triangles) roots.insert(sets.find(static_cast<std::uint32_t>(t[0])));
    return static_cast<int>(roots.size());
}

} // namespace

TEST(CutClosure, ACutThroughTheObjectLeavesTwoClosedPieces)
{
    const Closed c = cut_box({});
    EXPECT_EQ(c.counts.faces, 1u);
    EXPECT_EQ(c.counts.slit_faces, 0u);
    EXPECT_EQ(c.counts.open_chains, 0u);
    expect_closed(c);
    EXPECT_EQ(pieces(c), 2);
    expect_pieces_on_one_side(c);
    const auto [volume, crack] = volume_and_crack_area(c);
    EXPECT_NEAR(volume, 5.9 * 3.9 * 3.9, 1e-9);
    EXPECT_NEAR(crack, 2.0 * 3.9 * 3.9,
                1e-9); // the whole cross-section, once per side
}

TEST(CutClosure, ASlitIsClosedAlongItsFrontInsideTheObject)
{
    // Cut only where the plane's crossings lie above z = 1.9: the tetrahedra of the top two layers
    // of cubes (z from 2 to 4), so the crack runs from the top face down to z = 2.
    for (const double step : {0.37, 0.39}) {
        const Closed c = cut_box([](const Eigen::Vector3d& p) { return p.z() > 1.9; }, step);
        EXPECT_EQ(c.counts.faces, 1u);
        EXPECT_EQ(c.counts.slit_faces, 1u);
        EXPECT_EQ(c.counts.open_chains, 0u);
        expect_closed(c);
        EXPECT_EQ(pieces(c), 1);
        const auto [volume, crack] = volume_and_crack_area(c);
        EXPECT_NEAR(volume, 5.9 * 3.9 * 3.9, 1e-9);
        // S (y, z in [0.05, 3.95]) and R (z in [2, 4]) intersected, once per side.
        EXPECT_NEAR(crack, 2.0 * 3.9 * (3.95 - 2.0), 1e-9);
    }
}

TEST(CutClosure, ASlitInsideACornerOnlyOpensTwoFaces)
{
    // The crack fills the corner y < 2, z > 2 of the cross-section: it reaches the top and the y =
    // 0.05 face, and its front turns a corner inside the object. On a surface whose vertices avoid
    // the front, and on one whose vertices lie on it (where a front point is kept a thousandth of a
    // crossing off the split one, hence the looser area).
    for (const double step : {0.37, 0.39}) {
        const Closed c = cut_box([](const Eigen::Vector3d& p) { return p.z() > 1.9 && p.y() < 2.1; }, step);
        EXPECT_EQ(c.counts.slit_faces, 1u) << step;
        EXPECT_EQ(c.counts.open_chains, 0u) << step;
        expect_closed(c);
        const auto [volume, crack] = volume_and_crack_area(c);
        EXPECT_NEAR(volume, 5.9 * 3.9 * 3.9, 1e-9) << step;
        EXPECT_NEAR(crack, 2.0 * (2.0 - 0.05) * (3.95 - 2.0), step == 0.37 ? 1e-9 : 1e-3) << step;
    }
}

TEST(CutClosure, ACavityLeavesAHoleInTheFaces)
{
    // Through: each face is the cross-section less the cavity's. A slit down to z = 2 through the
    // cavity's upper part: its front runs into the void.
    struct Case {
        std::function<bool(const Eigen::Vector3d&)> inside;
        std::size_t slit_faces;
        int pieces;
        double crack;
    };
    for (const Case& k : {Case{{}, 0, 2, 2.0 * (3.9 * 3.9 - 1.4 * 1.4)},
                          Case{[](const Eigen::Vector3d& p) { return p.z() > 1.9; }, 1, 1, 2.0 * (3.9 * (3.95 - 2.0) - 1.4 * (2.7 - 2.0))}}) {
        SCOPED_TRACE(k.slit_faces ? "slit" : "through");
        const Closed c = cut_box(k.inside, 0.37, true);
        EXPECT_EQ(c.counts.faces, 1u);
        EXPECT_EQ(c.counts.slit_faces, k.slit_faces);
        EXPECT_EQ(c.counts.open_chains, 0u);
        expect_closed(c);
        EXPECT_EQ(pieces(c), k.pieces);
        const auto [volume, crack] = volume_and_crack_area(c);
        EXPECT_NEAR(volume, 5.9 * 3.9 * 3.9 - 1.2 * 1.4 * 1.4, 1e-9);
        EXPECT_NEAR(crack, k.crack, 1e-9);
    }
}

TEST(CutClosure, TwoCrossingCutsLeaveFourClosedPieces)
{
    // Across at x = 3.1, then lengthwise at y = 2.1: the second splits the first's faces too, and
    // its own faces run over them (each side of the first cut its own loop).
    const PlaneCut lengthwise{Eigen::Vector3d::UnitY(), 2.1};
    const Closed c = cut_box({}, 0.37, false, &lengthwise);
    EXPECT_EQ(c.counts.faces, 3u); // one across, two lengthwise (one each side of the first)
    EXPECT_EQ(c.counts.open_chains, 0u);
    expect_closed(c);
    EXPECT_EQ(pieces(c), 4);
    expect_pieces_on_one_side(c);
    const double across = volume_and_crack_area(c).second, along = volume_and_crack_area(c, 2.1).second;
    EXPECT_NEAR(volume_and_crack_area(c).first, 5.9 * 3.9 * 3.9, 1e-9);
    EXPECT_NEAR(across, 2.0 * 3.9 * 3.9, 1e-9);
    EXPECT_NEAR(along, 2.0 * 5.9 * 3.9, 1e-9);
}

TEST(CutClosure, ASlitAcrossAnEarlierCutKeepsEachSideOnItsPiece)
{
    // Through at x = 3.1, then a slit at y = 2.1 down to z = 2: the slit's front crosses both
    // faces of the first cut, which lie on each other at rest; each front point must go with its
    // own piece.
    const PlaneCut lengthwise{Eigen::Vector3d::UnitY(), 2.1};
    const Closed c = cut_box({}, 0.37, false, &lengthwise, [](const Eigen::Vector3d& p) { return p.z() > 1.9; });
    EXPECT_EQ(c.counts.slit_faces, 2u); // one on each side of the first cut
    EXPECT_EQ(c.counts.open_chains, 0u);
    expect_closed(c);
    EXPECT_EQ(pieces(c), 2);
    expect_pieces_on_one_side(c, {0}); // the slit joins the two sides of its own cut
    EXPECT_NEAR(volume_and_crack_area(c).first, 5.9 * 3.9 * 3.9, 1e-9);
    EXPECT_NEAR(volume_and_crack_area(c, 2.1).second, 2.0 * 5.9 * (3.95 - 2.0), 1e-9);
}

namespace {

constexpr double k_bend_radius = 4.0;
const Eigen::Vector2d k_bend_centre(7.1, 2.0);

/// A blade's sweep bending through the box: patches 2 degrees wide along the arc of radius 4 about
/// (7.1, 2) in x-y (through x = 3.1 at y = 2), from y = -0.5 to `to_y`, through all of z.
CutSurface bent_sweep(double to_y)
{
    return vox::test::arc_sweep(k_bend_centre, k_bend_radius, std::asin(-2.5 / k_bend_radius), std::asin((to_y - 2.0) / k_bend_radius),
                                2.0 * M_PI / 180.0);
}

/// The area of the closed surface's triangles on the bent crack (facing along x, away from the
/// box's own faces) and how far their corners and middles lie from the bend's cylinder.
std::pair<double, double> bent_crack(const Closed& c)
{
    double area = 0.0, off = 0.0;
    for (const Eigen::Vector3i& t : c.triangles) {
        std::array<Eigen::Vector3d, 4> x;
        for (int k = 0; k < 3; ++k) x[static_cast<std::size_t>(k)] = c.points[static_cast<std::size_t>(t[k])].rest_m;
        const Eigen::Vector3d n = (x[1] - x[0]).cross(x[2] - x[0]);
        if (std::abs(n.normalized().x()) < 0.8 || std::min({x[0].x(), x[1].x(), x[2].x()}) < 0.5 || std::max({x[0].x(), x[1].x(), x[2].x()}) > 5.5)
            continue;
        area += 0.5 * n.norm();
        x[3] = (x[0] + x[1] + x[2]) / 3.0;
        for (const Eigen::Vector3d& p : x) off = std::max(off, std::abs((p.head<2>() - k_bend_centre).norm() - k_bend_radius));
    }
    return {area, off};
}

} // namespace

TEST(CutClosure, ABentSweepIsClosedAndItsFacesFollowTheBend)
{
    const CutSurface sweep = bent_sweep(4.5);
    const Closed c = closed_box([&](XfemModel& model) { return std::vector<CutReport>{model.cut(sweep, 0)}; });
    EXPECT_EQ(c.counts.faces, 1u);
    EXPECT_EQ(c.counts.open_chains, 0u);
    expect_closed(c);
    EXPECT_EQ(pieces(c), 2);
    expect_pieces_on_one_side(c);
    EXPECT_NEAR(volume_and_crack_area(c).first, 5.9 * 3.9 * 3.9, 1e-9);
    // The crack through the box: its arc between y = 0.05 and 3.95, 3.9 high, on both sides, to
    // within what the cut's planes in 1 m tetrahedra make of the bend (chords of tetrahedron edges
    // up to 1.7 m long: 1.7^2 / 8 r off the arc); a face triangulated from its rim alone would lie
    // 0.5 m off it in the middle.
    const auto [area, off] = bent_crack(c);
    EXPECT_NEAR(area, 2.0 * 3.9 * 2.0 * k_bend_radius * std::asin(1.95 / k_bend_radius), 0.01 * area);
    EXPECT_LT(off, 0.1);
}

TEST(CutClosure, ABentSlitIsClosedAlongItsFront)
{
    const CutSurface sweep = bent_sweep(2.5); // from y = -0.5 to 2.5: into the box and stopping inside
    const Closed c = closed_box([&](XfemModel& model) { return std::vector<CutReport>{model.cut(sweep, 0)}; });
    EXPECT_EQ(c.counts.slit_faces, 1u);
    EXPECT_EQ(c.counts.open_chains, 0u);
    expect_closed(c);
    EXPECT_EQ(pieces(c), 1);
    EXPECT_NEAR(volume_and_crack_area(c).first, 5.9 * 3.9 * 3.9, 1e-9);
    EXPECT_LT(bent_crack(c).second, 0.1);
}

TEST(CutClosure, ASweptSlitAcrossAnEarlierPlaneCutIsClosed)
{
    // Through at x = 3.1, then a blade's sweep (one patch) at y = 2.3 from the top down to z = 2,
    // across the first cut: near the sweep its level is the nodes', beyond it its surface's, so
    // the first cut's large crack faces, reaching from near it to far, cross it where it is.
    CutSurface sweep;
    CutPatch p;
    p.corners = {{1.5, 2.3, 2.0}, {4.6, 2.3, 2.0}, {4.6, 2.3, 4.5}, {1.5, 2.3, 4.5}};
    p.normal = Eigen::Vector3d::UnitY();
    sweep.add(p);
    const Closed c = closed_box([&](XfemModel& model) {
        return std::vector<CutReport>{model.cut(PlaneCut{Eigen::Vector3d::UnitX(), 3.1}), model.cut(sweep, 0)};
    });
    EXPECT_EQ(c.counts.open_chains, 0u);
    expect_closed(c);
    EXPECT_EQ(pieces(c), 2);
    EXPECT_NEAR(volume_and_crack_area(c).first, 5.9 * 3.9 * 3.9, 1e-9);
}
