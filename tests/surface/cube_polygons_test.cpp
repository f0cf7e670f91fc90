#include "surface/cube_polygons.hpp"

#include <gtest/gtest.h>

#include <map>
#include <random>
#include <set>

using namespace vox::surface;

namespace {

/// The (corner, edge) pairs that must carry a crossing vertex: a present corner whose edge leads
/// to an absent corner or through a disconnected face.
std::set<std::pair<int, int>> expected_crossings(std::uint8_t present, std::uint16_t connected)
{
    std::set<std::pair<int, int>> out;
    for (int e = 0; e < 12; ++e) {
        const int a = edge_corners[e][0], b = edge_corners[e][1];
        const bool pa = (present >> a) & 1, pb = (present >> b) & 1;
        const bool joined = pa && pb && ((connected >> e) & 1);
        if (pa && !joined) out.insert({a, e});
        if (pb && !joined) out.insert({b, e});
    }
    return out;
}

void check_configuration(std::uint8_t present, std::uint16_t connected)
{
    SCOPED_TRACE(testing::Message() << "present " << int(present) << " connected " << connected);
    const auto loops = polygonise_cube(present, connected);
    std::multiset<std::pair<int, int>> crossings;
    for (const CubeLoop& loop : loops) {
        ASSERT_GE(loop.vertices.size(), loop.needs_centre ? 2u : 3u);
        EXPECT_TRUE(loop.closed);
        for (const CubeVertex& v : loop.vertices) {
            EXPECT_TRUE((present >> v.corner) & 1);
            if (v.kind == CubeVertex::Kind::crossing) crossings.insert({v.corner, v.index});
        }
    }
    // Every crossing lies on exactly one loop, and nothing else does.
    const auto expect = expected_crossings(present, connected);
    EXPECT_EQ(crossings.size(), expect.size());
    for (const auto& c : expect) EXPECT_EQ(crossings.count(c), 1u);
}

} // namespace

TEST(CubePolygons, SingleCornerIsOneTriangleFacingAway)
{
    const CubeCase c = triangulate_cube(0x01, 0);
    ASSERT_EQ(c.triangles.size(), 1u);
    std::array<std::array<double, 3>, 3> p;
    for (int k = 0; k < 3; ++k) p[k] = cube_vertex_position(c.triangles[0][k]);
    const double ux = p[1][0] - p[0][0], uy = p[1][1] - p[0][1], uz = p[1][2] - p[0][2];
    const double vx = p[2][0] - p[0][0], vy = p[2][1] - p[0][1], vz = p[2][2] - p[0][2];
    const double nx = uy * vz - uz * vy, ny = uz * vx - ux * vz, nz = ux * vy - uy * vx;
    EXPECT_GT(nx + ny + nz, 0.0); // away from corner 0 at the origin
}

TEST(CubePolygons, EveryPresenceMaskWithConnectedFacesGivesClosedLoops)
{
    for (int present = 1; present < 256; ++present) check_configuration(static_cast<std::uint8_t>(present), 0xfff);
}

TEST(CubePolygons, RandomDisconnectionsGiveClosedLoops)
{
    std::mt19937 rng(3);
    for (int k = 0; k < 20000; ++k)
        check_configuration(static_cast<std::uint8_t>(rng() & 0xff), static_cast<std::uint16_t>(rng() & 0xfff));
}

TEST(CubePolygons, DiagonalCornersOnAFaceAreSeparated)
{
    // Corners 0 and 3 share only a face diagonal: two separate triangles, no shared vertex.
    const auto loops = polygonise_cube(0x09, 0xfff);
    ASSERT_EQ(loops.size(), 2u);
    EXPECT_EQ(loops[0].vertices.size(), 3u);
    EXPECT_EQ(loops[1].vertices.size(), 3u);
}

TEST(CubePolygons, TheEndOfACutGoesThroughFaceAndCubeCentres)
{
    // All eight corners present, one disconnected edge: the tip of a wall inside the cube.
    const auto loops = polygonise_cube(0xff, 0xfff & ~1);
    ASSERT_EQ(loops.size(), 1u);
    EXPECT_TRUE(loops[0].needs_centre);
    EXPECT_EQ(loops[0].vertices.size(), 4u); // two crossings on the edge, two face centres
    EXPECT_EQ(triangulate_cube(0xff, 0xfff & ~1).triangles.size(), 4u);
}
