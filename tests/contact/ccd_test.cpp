// Continuous collision detection: hand-made motions with known answers, the benchmark query files
// with ground truth (no false negatives allowed), and malformed query files.

#include "contact/ccd_queries.hpp"
#include "core/error.hpp"
#include "test_support.hpp"

#include <gtest/gtest.h>

#include <Eigen/Geometry>

#include <filesystem>
#include <fstream>
#include <limits>
#include <random>

using namespace vox::contact;
using Eigen::Vector3d;
using Points = std::array<Vector3d, 4>;

namespace {
const Points triangle_at0{Vector3d(0.2, 0.2, 1.0), Vector3d(0, 0, 0), Vector3d(1, 0, 0), Vector3d(0, 1, 0)};

Points moved(Points p, const Vector3d& vertex_end)
{
    p[0] = vertex_end;
    return p;
}
} // namespace

TEST(Ccd, VertexThroughTheFaceHits)
{
    EXPECT_TRUE(vertex_face_ccd(triangle_at0, moved(triangle_at0, {0.2, 0.2, -1.0})));
    // Stopping exactly on the face at t = 1 still counts.
    EXPECT_TRUE(vertex_face_ccd(triangle_at0, moved(triangle_at0, {0.2, 0.2, 0.0})));
    // Through an edge and through a corner.
    EXPECT_TRUE(vertex_face_ccd(moved(triangle_at0, {0.5, 0.0, 1.0}), moved(triangle_at0, {0.5, 0.0, -1.0})));
    EXPECT_TRUE(vertex_face_ccd(moved(triangle_at0, {0.0, 0.0, 1.0}), moved(triangle_at0, {0.0, 0.0, -1.0})));
}

TEST(Ccd, VertexBesideOrShortOfTheFaceMisses)
{
    EXPECT_FALSE(vertex_face_ccd(moved(triangle_at0, {0.8, 0.8, 1.0}), moved(triangle_at0, {0.8, 0.8, -1.0})));
    EXPECT_FALSE(vertex_face_ccd(triangle_at0, moved(triangle_at0, {0.2, 0.2, 1e-9})));
    // Sliding in the face's plane for the whole step: inside touches, outside does not.
    EXPECT_TRUE(vertex_face_ccd(moved(triangle_at0, {0.1, 0.1, 0}), moved(triangle_at0, {0.3, 0.3, 0})));
    EXPECT_FALSE(vertex_face_ccd(moved(triangle_at0, {1.1, 1.1, 0}), moved(triangle_at0, {1.3, 1.3, 0})));
}

TEST(Ccd, MovingFaceSweepsOverAStillVertex)
{
    const Points at0{Vector3d(0.25, 0.25, 0.5), Vector3d(0, 0, 1), Vector3d(1, 0, 1), Vector3d(0, 1, 1)};
    const Points at1{Vector3d(0.25, 0.25, 0.5), Vector3d(0, 0, 0), Vector3d(1, 0, 0), Vector3d(0, 1, 0)};
    EXPECT_TRUE(vertex_face_ccd(at0, at1));
}

TEST(Ccd, EdgesCrossingOrApart)
{
    // Edge a along x at z = 1 moving down through edge b along y at z = 0.
    const Points at0{Vector3d(-1, 0, 1), Vector3d(1, 0, 1), Vector3d(0, -1, 0), Vector3d(0, 1, 0)};
    const Points at1{Vector3d(-1, 0, -1), Vector3d(1, 0, -1), Vector3d(0, -1, 0), Vector3d(0, 1, 0)};
    EXPECT_TRUE(edge_edge_ccd(at0, at1));
    // The same motion shifted past b's end.
    Points miss0 = at0, miss1 = at1;
    for (Points* p : {&miss0, &miss1}) {
        (*p)[2].y() += 3;
        (*p)[3].y() += 3;
    }
    EXPECT_FALSE(edge_edge_ccd(miss0, miss1));
    // Parallel edges passing one above the other without meeting.
    const Points par0{Vector3d(0, 0, 1), Vector3d(1, 0, 1), Vector3d(0, 1, 0), Vector3d(1, 1, 0)};
    const Points par1{Vector3d(0, 0, 0.5), Vector3d(1, 0, 0.5), Vector3d(0, 1, 0), Vector3d(1, 1, 0)};
    EXPECT_FALSE(edge_edge_ccd(par0, par1));
}

TEST(Ccd, TimeOfImpactIsALowerBoundWithinTheResolution)
{
    // The vertex falls from z = 1 to z = -3: it meets the face at t = 1/4.
    const double vf = vertex_face_toi(triangle_at0, moved(triangle_at0, {0.2, 0.2, -3.0}));
    EXPECT_LE(vf, 0.25);
    EXPECT_GT(vf, 0.25 - 1e-6);
    // Edge (0,0,1)-(1,0,1) dropping to z = -1 meets edge (0.5,-1,0)-(0.5,1,0) at t = 1/2.
    const Points e0{Vector3d(0, 0, 1), Vector3d(1, 0, 1), Vector3d(0.5, -1, 0), Vector3d(0.5, 1, 0)};
    const Points e1{Vector3d(0, 0, -1), Vector3d(1, 0, -1), Vector3d(0.5, -1, 0), Vector3d(0.5, 1, 0)};
    const double ee = edge_edge_toi(e0, e1);
    EXPECT_LE(ee, 0.5);
    EXPECT_GT(ee, 0.5 - 1e-6);
    // No contact: infinity, and the yes/no tests agree.
    EXPECT_EQ(vertex_face_toi(moved(triangle_at0, {0.8, 0.8, 1.0}), moved(triangle_at0, {0.8, 0.8, -1.0})),
              std::numeric_limits<double>::infinity());
    EXPECT_TRUE(vertex_face_ccd(triangle_at0, moved(triangle_at0, {0.2, 0.2, -3.0})));
}

TEST(Ccd, TranslatingQueriesFindTheKnownTimesOfImpact)
{
    // The cases above as translations: exact to rounding, and never late.
    const std::array<Vector3d, 3> face{Vector3d(0, 0, 0), Vector3d(1, 0, 0), Vector3d(0, 1, 0)};
    const double vf = translating_vertex_face_toi({0.2, 0.2, 1.0}, {0, 0, -4}, face);
    EXPECT_LE(vf, 0.25);
    EXPECT_GT(vf, 0.25 - 1e-12);
    const double ee = translating_edge_edge_toi({Vector3d(0, 0, 1), Vector3d(1, 0, 1)}, {0, 0, -2}, {Vector3d(0.5, -1, 0), Vector3d(0.5, 1, 0)});
    EXPECT_LE(ee, 0.5);
    EXPECT_GT(ee, 0.5 - 1e-12);
    EXPECT_EQ(translating_vertex_face_toi({0.8, 0.8, 1.0}, {0, 0, -2}, face), std::numeric_limits<double>::infinity()); // beside the face
    EXPECT_EQ(translating_vertex_face_toi({0.2, 0.2, 1.0}, {0, 0, -0.5}, face), std::numeric_limits<double>::infinity()); // short of it
    // On a corner shared with the next face, at t = 1/2: found (conservative at the boundary).
    EXPECT_NEAR(translating_vertex_face_toi({1.0, 0.0, 1.0}, {0, 0, -2}, face), 0.5, 1e-12);
    // A move within the face's plane (the general query answers): the same as it.
    EXPECT_EQ(translating_vertex_face_toi({-1, 0.2, 0}, {2, 0, 0}, face),
              vertex_face_toi({Vector3d(-1, 0.2, 0), face[0], face[1], face[2]}, {Vector3d(1, 0.2, 0), face[0], face[1], face[2]}));
}

TEST(Ccd, TranslatingQueriesAgreeWithTheGeneralOnesOnRandomMotions)
{
    // Random triangles and edges a few mm across, moved by up to 6 mm: the translating queries
    // find the contacts the general ones (halving to 2^-24) find, and no others; their times are
    // the coplanarity root worked out again in long double (never later, within 1e-9), and the
    // general ones' are no later than theirs (bounding the conditions over whole intervals, these
    // can leave a few intervals before the contact standing).
    std::mt19937 random(7);
    std::uniform_real_distribution<double> coordinate(-2.0, 2.0);
    auto point = [&] { return Vector3d(coordinate(random), coordinate(random), coordinate(random)); };
    using Long = Eigen::Matrix<long double, 3, 1>;
    auto root = [](const Vector3d& value_point, const Vector3d& move, const Vector3d& normal_a, const Vector3d& normal_b) {
        const Long a = normal_a.cast<long double>(), b = normal_b.cast<long double>(), value = value_point.cast<long double>(),
                   rate = move.cast<long double>();
        const Long n = a.cross(b);
        return -value.dot(n) / rate.dot(n);
    };
    const double infinity = std::numeric_limits<double>::infinity();
    int vf_hits = 0, ee_hits = 0;
    for (int k = 0; k < 4000; ++k) {
        const std::array<Vector3d, 3> face{point(), point(), point()};
        const Vector3d v = point(), move = 1.5 * point();
        const double fast = translating_vertex_face_toi(v, move, face);
        const double general = vertex_face_toi({v, face[0], face[1], face[2]}, {v + move, face[0], face[1], face[2]});
        ASSERT_EQ(fast == infinity, general == infinity) << k;
        if (fast < infinity) {
            const long double exact = root(v - face[0], move, face[1] - face[0], face[2] - face[0]);
            EXPECT_LE(fast, exact + 1e-12L) << k;
            EXPECT_LT(exact - fast, 1e-9L) << k;
            EXPECT_LE(general, fast) << k;
            ++vf_hits;
        }
        const std::array<Vector3d, 2> edge{point(), point()}, other{point(), point()};
        const double fast_ee = translating_edge_edge_toi(edge, move, other);
        const double general_ee = edge_edge_toi({edge[0], edge[1], other[0], other[1]}, {edge[0] + move, edge[1] + move, other[0], other[1]});
        ASSERT_EQ(fast_ee == infinity, general_ee == infinity) << k;
        if (fast_ee < infinity) {
            const long double exact = -root(other[0] - edge[0], move, edge[1] - edge[0], other[1] - other[0]);
            EXPECT_LE(fast_ee, exact + 1e-12L) << k;
            EXPECT_LT(exact - fast_ee, 1e-9L) << k;
            EXPECT_LE(general_ee, fast_ee) << k;
            ++ee_hits;
        }
    }
    EXPECT_GT(vf_hits, 50); // the motions do meet often enough to compare times
    EXPECT_GT(ee_hits, 50);
}

TEST(Ccd, BenchmarkQueriesHaveNoFalseNegatives)
{
    const std::filesystem::path root = VOX_SOURCE_DIR "/data/ccd-queries/unit-tests";
    std::size_t queries = 0;
    for (const char* kind : {"vertex-face", "edge-edge"})
        for (const auto& entry : std::filesystem::directory_iterator(root / kind)) {
            const auto q = read_ccd_queries(entry.path());
            queries += q.size();
            const CcdScore s = score_ccd(q, std::string(kind) == "vertex-face");
            EXPECT_EQ(s.false_negatives, 0u) << entry.path();
            EXPECT_EQ(s.true_positives + s.false_positives + s.false_negatives + s.true_negatives, q.size());
            EXPECT_GT(s.true_negatives, 0u) << entry.path() << ": a test that says yes to everything proves nothing";
        }
    EXPECT_EQ(queries, 324u);
}

TEST(Ccd, MalformedQueryFilesNameTheFileAndLine)
{
    const auto dir = vox::test::fresh_dir("ccd_bad");
    auto refused = [&](const std::string& name, const std::string& text, const std::string& problem) {
        const auto path = dir / name;
        std::ofstream(path) << text;
        try {
            static_cast<void>(read_ccd_queries(path));
            ADD_FAILURE() << name << " was accepted";
        } catch (const vox::InputError& e) {
            const std::string message = e.what();
            EXPECT_NE(message.find(path.string()), std::string::npos) << message;
            EXPECT_NE(message.find(problem), std::string::npos) << message;
        }
    };
    std::string eight;
    for (int i = 0; i < 8; ++i) eight += "1,1,2,1,3,1,0\n";
    refused("short.csv", eight.substr(0, eight.size() - 14), "the last one is cut short");
    refused("fields.csv", "1,1,2,1,3,1\n", "line 1: expected 7 comma-separated integers");
    refused("fraction.csv", "1,1,2.5,1,3,1,0\n", "line 1: coordinate 2 is not a fraction");
    refused("zero.csv", "1,0,2,1,3,1,0\n", "line 1: zero denominator");
    refused("truth.csv", "1,1,2,1,3,1,2\n", "ground truth must be 0 or 1");
    refused("empty.csv", "", "holds no query");
    // Denominators beyond 64 bits are read (as doubles).
    std::ofstream(dir / "big.csv") << [] {
        std::string s;
        for (int i = 0; i < 8; ++i) s += "1,36893488147419103232,2,1,3,1,0\n";
        return s;
    }();
    EXPECT_EQ(read_ccd_queries(dir / "big.csv").size(), 1u);
}

#include "contact/mesh_ccd.hpp"

namespace {
/// A closed box mesh (12 triangles) of `size` centred at `centre`.
MovingMesh box(const Vector3d& centre_start, const Vector3d& centre_end, double size)
{
    MovingMesh m;
    for (int c = 0; c < 8; ++c) {
        const Vector3d corner(c & 1 ? 0.5 : -0.5, c & 2 ? 0.5 : -0.5, c & 4 ? 0.5 : -0.5);
        m.start.push_back(centre_start + size * corner);
        m.end.push_back(centre_end + size * corner);
    }
    m.triangles = {{0, 2, 1}, {1, 2, 3}, {4, 5, 6}, {5, 7, 6}, {0, 1, 4}, {1, 5, 4},
                   {2, 6, 3}, {3, 6, 7}, {0, 4, 2}, {2, 4, 6}, {1, 3, 5}, {3, 7, 5}};
    return m;
}

/// A still floor: an n x n grid of squares over [-1, 1]^2 at z = 0.
MovingMesh floor_mesh(int n)
{
    MovingMesh m;
    for (int j = 0; j <= n; ++j)
        for (int i = 0; i <= n; ++i) m.start.emplace_back(-1.0 + 2.0 * i / n, -1.0 + 2.0 * j / n, 0.0);
    m.end = m.start;
    for (int j = 0; j < n; ++j)
        for (int i = 0; i < n; ++i) {
            const int v = j * (n + 1) + i;
            m.triangles.emplace_back(v, v + 1, v + n + 2);
            m.triangles.emplace_back(v, v + n + 2, v + n + 1);
        }
    return m;
}
} // namespace

TEST(MeshCcd, AFallingBoxHitsTheFloorOnlyWhenItReachesIt)
{
    const MovingMesh floor = floor_mesh(16);
    // Falls from 0.5 to 0.2 above the floor: no contact.
    EXPECT_TRUE(mesh_ccd(box({0.1, 0.1, 0.6}, {0.1, 0.1, 0.3}, 0.2), floor).empty());
    // Falls until its bottom face is 0.05 below the floor: only the bottom corners (0-3) reach it.
    const auto hits = mesh_ccd(box({0.1, 0.1, 0.6}, {0.1, 0.1, 0.05}, 0.2), floor);
    ASSERT_FALSE(hits.empty());
    std::size_t corners = 0;
    for (const MeshContact& c : hits)
        if (c.kind == MeshContact::vertex_a_face_b) {
            ++corners;
            EXPECT_LT(c.a, 4u); // bottom corners: z = centre - 0.1
        }
    EXPECT_GE(corners, 4u);
    // Moving sideways far from the floor's edge: nothing.
    EXPECT_TRUE(mesh_ccd(box({3, 3, 0.05}, {4, 3, -0.05}, 0.05), floor).empty());
}
