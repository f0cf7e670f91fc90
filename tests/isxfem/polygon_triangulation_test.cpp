// Ear clipping: a convex and a non-convex (L-shaped, then comb-shaped) polygon in either
// orientation are covered exactly (the triangles' areas add up to the polygon's) by n - 2
// counter-clockwise triangles.

#include "isxfem/polygon_triangulation.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>

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
