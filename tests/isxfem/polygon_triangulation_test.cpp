// Ear clipping: a convex and a non-convex (L-shaped, then comb-shaped) polygon in either
// orientation are covered exactly (the triangles' areas add up to the polygon's) by n - 2
// counter-clockwise triangles. Holes: two squares in a square and a square on its own come out as
// two faces, the holes bridged in so that the triangulated face covers the square less its holes;
// a hole in nothing is left out and counted. Points added inside a triangulation: inside a
// triangle, on an inner edge (both triangles beside it split), on the boundary (left out).

#include "isxfem/polygon_triangulation.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <map>

using vox::isxfem::triangulate_polygon;

namespace {

double signed_area(const std::vector<Eigen::Vector2d>& p)
{
    double a = 0.0;
    for (std::size_t i = 0; i < p.size(); ++i) a += p[i].x() * p[(i + 1) % p.size()].y() - p[(i + 1) % p.size()].x() * p[i].y();
    return 0.5 * a;
}

void expect_covered(std::vector<Eigen::Vector2d> polygon)
{
    for (bool reversed : {false, true}) {
        if (reversed) std::reverse(polygon.begin(), polygon.end());
        const auto t = triangulate_polygon(polygon);
        ASSERT_EQ(t.size(), polygon.size() - 2);
        double total = 0.0;
        for (const auto& f : t) {
            const double a = signed_area({polygon[static_cast<std::size_t>(f[0])], polygon[static_cast<std::size_t>(f[1])],
                                          polygon[static_cast<std::size_t>(f[2])]});
            EXPECT_GT(a, 0.0);
            total += a;
        }
        EXPECT_NEAR(total, std::abs(signed_area(polygon)), 1e-12);
    }
}

} // namespace

TEST(PolygonTriangulation, CoversConvexAndNonConvexPolygons)
{
    expect_covered({{0, 0}, {2, 0}, {3, 1}, {2, 2}, {0, 2}});
    expect_covered({{0, 0}, {3, 0}, {3, 1}, {1, 1}, {1, 3}, {0, 3}});                        // L
    expect_covered({{0, 0}, {5, 0}, {5, 3}, {4, 3}, {4, 1}, {3, 1}, {3, 3}, {2, 3}, {2, 1}, {1, 1}, {1, 3}, {0, 3}}); // comb
    EXPECT_TRUE(triangulate_polygon({{0, 0}, {1, 0}}).empty());
}

TEST(PolygonTriangulation, BridgesHolesIntoTheFaceAroundThem)
{
    auto square = [](double x0, double y0, double side, bool clockwise) {
        std::vector<Eigen::Vector2d> p{{x0, y0}, {x0 + side, y0}, {x0 + side, y0 + side}, {x0, y0 + side}};
        if (clockwise) std::reverse(p.begin(), p.end());
        return p;
    };
    const std::vector<std::vector<Eigen::Vector2d>> loops{square(0, 0, 10, false), square(2, 2, 2, true), square(6, 5, 3, true),
                                                          square(20, 0, 4, false), square(30, 30, 1, true)};
    std::size_t left_out = 0;
    const auto faces = vox::isxfem::faces_with_holes(loops, left_out);
    EXPECT_EQ(left_out, 1u); // the hole at (30, 30) lies in no face
    ASSERT_EQ(faces.size(), 2u);
    EXPECT_EQ(faces[0].size(), 4u + 2u * (4u + 2u)); // each hole's corners, its bridge corner again, and the face's
    EXPECT_EQ(faces[1].size(), 4u);
    std::vector<Eigen::Vector2d> merged;
    for (const auto& c : faces[0]) merged.push_back(loops[c.loop][c.corner]);
    double covered = 0.0;
    for (const auto& t : triangulate_polygon(merged)) {
        const Eigen::Vector2d a = merged[static_cast<std::size_t>(t[0])], b = merged[static_cast<std::size_t>(t[1])], c = merged[static_cast<std::size_t>(t[2])];
        const double area = 0.5 * ((b - a).x() * (c - a).y() - (b - a).y() * (c - a).x());
        EXPECT_GE(area, 0.0);
        covered += area;
    }
    EXPECT_NEAR(covered, 100.0 - 4.0 - 9.0, 1e-9);
}

namespace {

double triangle_area(const std::vector<Eigen::Vector2d>& p, const std::array<int, 3>& t)
{
    const Eigen::Vector2d a = p[static_cast<std::size_t>(t[1])] - p[static_cast<std::size_t>(t[0])];
    const Eigen::Vector2d b = p[static_cast<std::size_t>(t[2])] - p[static_cast<std::size_t>(t[0])];
    return 0.5 * (a.x() * b.y() - a.y() * b.x());
}

} // namespace

TEST(PolygonTriangulation, APointInsideOrOnAnInnerEdgeSplitsWhatHoldsItAndOneOnTheBoundaryIsLeftOut)
{
    // A unit square as two triangles; points added inside one, on their shared diagonal, and on
    // the square's own edge (refused: splitting it would leave a vertex in the middle of the
    // neighbouring surface's edge). Every triangle stays counter-clockwise, the area stays 1, and
    // every edge inside is shared by exactly two triangles (no overlap, no gap).
    std::vector<Eigen::Vector2d> points{{0, 0}, {1, 0}, {1, 1}, {0, 1}};
    std::vector<std::array<int, 3>> triangles = triangulate_polygon(points);
    ASSERT_EQ(triangles.size(), 2u);
    auto check = [&](std::size_t count) {
        ASSERT_EQ(triangles.size(), count);
        double area = 0.0;
        std::map<std::pair<int, int>, int> uses;
        for (const auto& t : triangles) {
            EXPECT_GT(triangle_area(points, t), 0.0);
            area += triangle_area(points, t);
            for (int e = 0; e < 3; ++e) ++uses[{t[static_cast<std::size_t>(e)], t[static_cast<std::size_t>((e + 1) % 3)]}];
        }
        EXPECT_NEAR(area, 1.0, 1e-12);
        for (const auto& [edge, n] : uses) {
            EXPECT_EQ(n, 1);
            const bool boundary = edge.first < 4 && edge.second < 4 && (edge.first + 1) % 4 == edge.second;
            if (!boundary) EXPECT_EQ(uses.count({edge.second, edge.first}), 1u) << "inner edge " << edge.first << "-" << edge.second;
        }
    };
    const vox::isxfem::Location inside = vox::isxfem::locate(points, triangles, {0.7, 0.2});
    ASSERT_GE(inside.triangle, 0);
    EXPECT_EQ(inside.edge, -1);
    vox::isxfem::insert_point(points, triangles, inside, {0.7, 0.2}, 4);
    check(4);
    // The middle of the square lies on the diagonal both first triangles had (whichever it is now,
    // an inner edge or inside a triangle after the flips): it is taken either way.
    const vox::isxfem::Location middle = vox::isxfem::locate(points, triangles, {0.5, 0.5});
    ASSERT_GE(middle.triangle, 0);
    vox::isxfem::insert_point(points, triangles, middle, {0.5, 0.5}, 4);
    check(6u); // on an edge two triangles split in two, inside one splits in three: six either way
    EXPECT_LT(vox::isxfem::locate(points, triangles, {0.5, 0.0}).triangle, 0) << "on the square's edge";
    EXPECT_LT(vox::isxfem::locate(points, triangles, {1.5, 0.5}).triangle, 0) << "outside";
}

TEST(PolygonTriangulation, APointOnAnInnerEdgeSplitsBothTrianglesBesideIt)
{
    // Two triangles sharing the diagonal (0,0)-(1,1) of a unit square; its middle splits both.
    std::vector<Eigen::Vector2d> points{{0, 0}, {1, 0}, {1, 1}, {0, 1}};
    std::vector<std::array<int, 3>> triangles{{0, 1, 2}, {0, 2, 3}};
    const vox::isxfem::Location at = vox::isxfem::locate(points, triangles, {0.5, 0.5});
    ASSERT_GE(at.triangle, 0);
    ASSERT_GE(at.edge, 0);
    vox::isxfem::insert_point(points, triangles, at, {0.5, 0.5}, 4);
    ASSERT_EQ(triangles.size(), 4u);
    double area = 0.0;
    for (const auto& t : triangles) {
        EXPECT_GT(triangle_area(points, t), 0.0);
        EXPECT_TRUE(std::find(t.begin(), t.end(), 4) != t.end()) << "every triangle has the new point";
        area += triangle_area(points, t);
    }
    EXPECT_NEAR(area, 1.0, 1e-12);
}
