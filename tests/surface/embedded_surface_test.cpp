#include "surface/embedded_surface.hpp"

#include "grid/phantom.hpp"
#include "io/mesh_info.hpp"

#include <gtest/gtest.h>

#include <algorithm>

#include <map>
#include <queue>
#include <random>
#include <set>

using namespace vox;
using namespace vox::grid;
using vox::surface::EmbeddedSurface;
using vox::surface::SurfaceMesh;

namespace {

const std::vector<ElasticMaterial> k_materials{{lame_from_young_poisson(3e4, 0.45), 1000.0}};

BranchedGrid make_grid(const LabelGrid& labels, int levels = 2)
{
    return BranchedGrid(FineVoxels(labels, [](std::int32_t) { return 0; }), k_materials, levels);
}

LabelGrid from_coords(const std::vector<Coord>& coords, const Eigen::Matrix4d& t = Eigen::Matrix4d::Identity())
{
    LabelGrid g(t);
    for (const Coord& c : coords) g.set(c, 1);
    return g;
}

io::MeshInfo info(const SurfaceMesh& m)
{
    io::TriangleMesh t;
    t.vertices = m.positions;
    t.triangles = m.triangles;
    return io::mesh_info(t);
}

/// Connected pieces of a mesh through shared vertices.
std::size_t mesh_pieces(const SurfaceMesh& m)
{
    std::vector<int> parent(m.positions.size());
    std::iota(parent.begin(), parent.end(), 0);
    std::function<int(int)> find = [&](int x) { return parent[x] == x ? x : parent[x] = find(parent[x]); };
    for (const auto& t : m.triangles) {
        parent[find(t[1])] = find(t[0]);
        parent[find(t[2])] = find(t[0]);
    }
    std::set<int> roots;
    for (const auto& t : m.triangles) roots.insert(find(t[0]));
    return roots.size();
}

/// Connected pieces of the voxels (6-connectivity through connected faces), by breadth-first search.
std::size_t voxel_pieces(const FineVoxels& v)
{
    std::vector<bool> seen(v.slots(), false);
    std::size_t pieces = 0;
    for (std::uint32_t s = 0; s < v.slots(); ++s) {
        if (!v.alive(s) || seen[s]) continue;
        ++pieces;
        std::queue<std::uint32_t> frontier;
        frontier.push(s);
        seen[s] = true;
        while (!frontier.empty()) {
            const std::uint32_t a = frontier.front();
            frontier.pop();
            v.for_each_link(a, [&](std::uint32_t b, int) {
                if (!seen[b]) {
                    seen[b] = true;
                    frontier.push(b);
                }
            });
        }
    }
    return pieces;
}

void expect_closed_oriented(const SurfaceMesh& m)
{
    const io::MeshInfo i = info(m);
    EXPECT_TRUE(i.closed);
    EXPECT_TRUE(i.consistently_oriented);
    EXPECT_EQ(i.non_manifold_edges, 0u);
    EXPECT_EQ(i.boundary_edges, 0u);
}

/// A canonical form of the surface independent of slot numbering: triangles as triples of vertex
/// descriptions (kind, doubled rest position, owning voxel), rotated to start at the smallest;
/// and each vertex's embedding (element cell, element's first voxel, trilinear coordinates).
using VertexId = std::tuple<int, int, int, int, int, int, int>;
struct CanonicalSurface {
    std::multiset<std::array<VertexId, 3>> triangles;
    std::map<VertexId, std::tuple<int, int, int, int, int, int, double, double, double>> embedding;
};

CanonicalSurface canonical(const BranchedGrid& grid, const EmbeddedSurface& s)
{
    CanonicalSurface out;
    auto id = [&](std::uint32_t v) {
        const auto& x = s.vertices()[v];
        const Coord owner = grid.voxels().coord(x.voxel);
        return VertexId{static_cast<int>(x.key & 3), int(std::lround(2 * x.rest.x())), int(std::lround(2 * x.rest.y())),
                        int(std::lround(2 * x.rest.z())), owner.x(), owner.y(), owner.z()};
    };
    for (const auto& t : s.triangles()) {
        if (t[0] == no_index) continue;
        std::array<VertexId, 3> tri{id(t[0]), id(t[1]), id(t[2])};
        std::rotate(tri.begin(), std::min_element(tri.begin(), tri.end()), tri.end());
        out.triangles.insert(tri);
    }
    for (std::uint32_t v = 0; v < s.vertices().size(); ++v) {
        const auto& x = s.vertices()[v];
        if (x.users == 0) continue;
        const Element& e = grid.level(s.level()).elements[x.element];
        const Coord first = grid.voxels().coord(e.voxels.front());
        out.embedding[id(v)] = {e.cell.x(), e.cell.y(), e.cell.z(), first.x(), first.y(), first.z(),
                                x.local.x(), x.local.y(), x.local.z()};
    }
    return out;
}

} // namespace

TEST(EmbeddedSurface, SingleVoxelIsAnOctahedron)
{
    const BranchedGrid grid = make_grid(from_coords({{0, 0, 0}}), 1);
    const EmbeddedSurface s(grid, 1);
    EXPECT_EQ(s.triangle_count(), 8u);
    EXPECT_EQ(s.vertex_count(), 6u);
    const SurfaceMesh m = s.mesh(grid);
    expect_closed_oriented(m);
    EXPECT_NEAR(info(m).enclosed_volume_mm3, 1.0 / 6.0, 1e-12); // |x| + |y| + |z| <= 1/2
}

TEST(EmbeddedSurface, BoxesHaveTheExactTriangleCount)
{
    for (const auto& [nx, ny, nz] : {std::tuple{1, 1, 1}, std::tuple{2, 1, 1}, std::tuple{3, 4, 5}, std::tuple{8, 2, 6}}) {
        PhantomSpec spec = default_phantom(PhantomShape::block);
        spec.size_mm = {double(nx), double(ny), double(nz)};
        const BranchedGrid grid = make_grid(make_phantom(spec), 1);
        const EmbeddedSurface s(grid, 1);
        // 8 corner cubes (1 triangle), edge cubes (2), face cubes (2).
        const std::size_t a = nx - 1, b = ny - 1, c = nz - 1;
        EXPECT_EQ(s.triangle_count(), 8 + 2 * 4 * (a + b + c) + 2 * 2 * (a * b + b * c + a * c)) << nx << ny << nz;
        expect_closed_oriented(s.mesh(grid));
        EXPECT_GT(info(s.mesh(grid)).enclosed_volume_mm3, 0.0);
    }
}

TEST(EmbeddedSurface, VoxelsTouchingAlongAnEdgeGiveTwoClosedPieces)
{
    const BranchedGrid grid = make_grid(from_coords({{0, 0, 0}, {1, 1, 0}}), 1);
    const EmbeddedSurface s(grid, 1);
    const SurfaceMesh m = s.mesh(grid);
    EXPECT_EQ(m.triangles.size(), 16u);
    EXPECT_EQ(m.positions.size(), 12u);
    EXPECT_EQ(mesh_pieces(m), 2u);
    expect_closed_oriented(m);
}

TEST(EmbeddedSurface, MirroringTransformsKeepNormalsOutward)
{
    // LPS scans often have a negative determinant: the world-space winding must be flipped.
    const Eigen::Matrix4d mirror = Eigen::Vector4d(-0.5, 0.7, 1.3, 1.0).asDiagonal();
    const BranchedGrid grid = make_grid(from_coords({{0, 0, 0}, {1, 0, 0}, {1, 1, 0}}, mirror), 1);
    const SurfaceMesh m = EmbeddedSurface(grid, 1).mesh(grid);
    expect_closed_oriented(m);
    EXPECT_GT(info(m).enclosed_volume_mm3, 0.0);
}

TEST(EmbeddedSurface, PiecesMatchTheGridAndVolumeIsBounded)
{
    std::mt19937 rng(11);
    for (int trial = 0; trial < 5; ++trial) {
        LabelGrid labels(Eigen::Vector4d(0.5, 0.75, 1.25, 1.0).asDiagonal().toDenseMatrix());
        int count = 0;
        for (int z = -2; z < 10; ++z)
            for (int y = 0; y < 12; ++y)
                for (int x = -5; x < 7; ++x)
                    if (std::bernoulli_distribution(0.55)(rng)) {
                        labels.set({x, y, z}, 1);
                        ++count;
                    }
        BranchedGrid grid = make_grid(labels, 2);
        // Disconnect some faces too: pieces follow connectivity, not adjacency.
        std::vector<std::pair<Coord, int>> faces;
        for (int k = 0; k < 60; ++k)
            faces.emplace_back(Coord(int(rng() % 12) - 5, int(rng() % 12), int(rng() % 12) - 2), int(rng() % 3));
        grid.update({}, faces);
        const EmbeddedSurface s(grid, 2);
        const SurfaceMesh m = s.mesh(grid);
        expect_closed_oriented(m);
        EXPECT_EQ(mesh_pieces(m), voxel_pieces(grid.voxels()));
        // Marching cubes and the voxel boxes differ only inside cubes that carry surface, so
        // |V_mc - V_voxels| <= (surface cubes) x (voxel volume); each surface cube holds >= 1 triangle.
        const double voxel_volume = 0.5 * 0.75 * 1.25;
        const double v = info(m).enclosed_volume_mm3;
        EXPECT_LE(std::abs(v - count * voxel_volume), static_cast<double>(s.triangle_count()) * voxel_volume);
    }
}

TEST(EmbeddedSurface, RestDeformationAndAffineMotionAreReproduced)
{
    PhantomSpec spec = default_phantom(PhantomShape::sphere);
    spec.radius_mm = 5;
    const BranchedGrid grid = make_grid(make_phantom(spec), 2);
    const EmbeddedSurface s(grid, 2);
    const auto rest = grid.rest_node_positions(2);
    const SurfaceMesh at_rest = s.mesh(grid), deformed_rest = s.mesh(grid, rest);
    for (std::size_t i = 0; i < at_rest.positions.size(); ++i)
        EXPECT_LT((at_rest.positions[i] - deformed_rest.positions[i]).norm(), 1e-9);
    // Trilinear embedding reproduces any affine motion of the nodes exactly.
    Eigen::Matrix3d a;
    a << 1.1, 0.2, 0.0, -0.1, 0.9, 0.3, 0.05, 0.0, 1.2;
    const Eigen::Vector3d b(3, -2, 7);
    std::vector<Eigen::Vector3d> moved = rest;
    for (auto& p : moved)
        if (p.allFinite()) p = a * p + b;
    const SurfaceMesh m = s.mesh(grid, moved);
    for (std::size_t i = 0; i < m.positions.size(); ++i)
        EXPECT_LT((m.positions[i] - (a * at_rest.positions[i] + b)).norm(), 1e-9);
}

/// The lists the surface keeps up to date (triangles by vertex, vertices by element) hold exactly
/// what a count over its slots finds.
void expect_lists_match_slots(const BranchedGrid& grid, const EmbeddedSurface& s)
{
    const auto& vertices = s.vertices();
    std::vector<std::vector<std::uint32_t>> triangles(vertices.size());
    for (std::uint32_t t = 0; t < s.triangles().size(); ++t)
        if (s.triangles()[t][0] != grid::no_index)
            for (std::uint32_t v : s.triangles()[t]) triangles[v].push_back(t);
    std::vector<std::vector<std::uint32_t>> by_element(grid.level(s.level()).elements.size());
    for (std::uint32_t v = 0; v < vertices.size(); ++v) {
        const auto listed = s.vertex_triangles(v);
        ASSERT_TRUE(std::equal(listed.begin(), listed.end(), triangles[v].begin(), triangles[v].end())) << "vertex " << v;
        if (vertices[v].users) {
            ASSERT_EQ(vertices[v].element, grid.element_of(vertices[v].voxel, s.level())) << "vertex " << v;
            by_element[vertices[v].element].push_back(v);
        }
    }
    for (std::uint32_t e = 0; e < by_element.size(); ++e) {
        const auto span = s.element_vertices(e);
        std::vector<std::uint32_t> listed(span.begin(), span.end());
        std::sort(listed.begin(), listed.end());
        ASSERT_EQ(listed, by_element[e]) << "element " << e;
    }
}

TEST(EmbeddedSurface, LocalUpdatesEqualFreshExtraction)
{
    std::mt19937 rng(5);
    LabelGrid labels(Eigen::Vector4d(0.5, 0.75, 1.25, 1.0).asDiagonal().toDenseMatrix());
    for (int z = 0; z < 14; ++z)
        for (int y = -3; y < 11; ++y)
            for (int x = 0; x < 16; ++x)
                if (std::bernoulli_distribution(0.85)(rng)) labels.set({x, y, z}, 1 + (x > 8));
    BranchedGrid grid = make_grid(labels, 3);
    EmbeddedSurface s(grid, 2);
    std::vector<std::pair<Coord, int>> all_faces;
    for (int batch = 0; batch < 10; ++batch) {
        SCOPED_TRACE(testing::Message() << "batch " << batch);
        std::vector<Coord> removed;
        std::vector<std::pair<Coord, int>> faces;
        for (int k = 0; k < 5 + 6 * batch; ++k) {
            const Coord c(int(rng() % 16), int(rng() % 14) - 3, int(rng() % 14));
            if (k % 3 == 0)
                faces.emplace_back(c, int(rng() % 3));
            else
                removed.push_back(c);
        }
        const UpdateReport report = grid.update(removed, faces);
        s.update(grid, removed, faces, report);
        all_faces.insert(all_faces.end(), faces.begin(), faces.end());

        LabelGrid now(grid.voxels().index_to_world());
        for (std::uint32_t v = 0; v < grid.voxels().slots(); ++v)
            if (grid.voxels().alive(v)) now.set(grid.voxels().coord(v), grid.voxels().label(v));
        FineVoxels fresh_voxels(now, [](std::int32_t) { return 0; });
        for (const auto& [c, axis] : all_faces) {
            const std::uint32_t v = fresh_voxels.find(c);
            if (v != FineVoxels::missing && fresh_voxels.find(c + Coord::Unit(axis)) != FineVoxels::missing)
                fresh_voxels.disconnect(v, axis);
        }
        const BranchedGrid fresh_grid(std::move(fresh_voxels), k_materials, 3);
        const EmbeddedSurface fresh(fresh_grid, 2);
        EXPECT_EQ(s.triangle_count(), fresh.triangle_count());
        EXPECT_EQ(s.vertex_count(), fresh.vertex_count());
        const CanonicalSurface a = canonical(grid, s), b = canonical(fresh_grid, fresh);
        EXPECT_TRUE(a.triangles == b.triangles);
        EXPECT_TRUE(a.embedding == b.embedding);
        expect_closed_oriented(s.mesh(grid));
        expect_lists_match_slots(grid, s);
    }
    s.reembed(grid, 3); // another level: the lists follow
    expect_lists_match_slots(grid, s);
}

TEST(EmbeddedSurface, APartialCutLeavesOneClosedPieceWithAVisibleSlit)
{
    PhantomSpec spec = default_phantom(PhantomShape::block);
    spec.size_mm = {8, 8, 8};
    BranchedGrid grid = make_grid(make_phantom(spec), 2);
    EmbeddedSurface s(grid, 2);
    const std::size_t before = s.triangle_count();
    // A wall between x = 3 and x = 4 over half the block's height: it does not cut through.
    std::vector<std::pair<Coord, int>> faces;
    for (int y = 0; y < 8; ++y)
        for (int z = 0; z < 4; ++z) faces.emplace_back(Coord(3, y, z), 0);
    const UpdateReport report = grid.update({}, faces);
    s.update(grid, {}, faces, report);
    const SurfaceMesh m = s.mesh(grid);
    expect_closed_oriented(m);
    EXPECT_EQ(mesh_pieces(m), 1u);
    EXPECT_GT(s.triangle_count(), before);
    // Cutting the rest of the way separates the two halves.
    std::vector<std::pair<Coord, int>> rest;
    for (int y = 0; y < 8; ++y)
        for (int z = 4; z < 8; ++z) rest.emplace_back(Coord(3, y, z), 0);
    const UpdateReport report2 = grid.update({}, rest);
    s.update(grid, {}, rest, report2);
    expect_closed_oriented(s.mesh(grid));
    EXPECT_EQ(mesh_pieces(s.mesh(grid)), 2u);
}

TEST(EmbeddedSurface, WindowedSincSmoothingTakesOutSliceTerracesAndKeepsTheVolume)
{
    // A ball of radius 20 mm on CT-like voxels (1 x 1 x 2.5 mm): its surface shows slice terraces.
    constexpr double r = 20.0;
    const Eigen::Vector3d centre(30.0, 30.0, 30.0), spacing(1.0, 1.0, 2.5);
    LabelGrid labels(Eigen::Vector4d(spacing.x(), spacing.y(), spacing.z(), 1.0).asDiagonal().toDenseMatrix());
    int count = 0;
    for (int k = 0; k < 25; ++k)
        for (int j = 0; j < 61; ++j)
            for (int i = 0; i < 61; ++i)
                if ((Eigen::Vector3d(i, j, k).cwiseProduct(spacing) - centre).norm() <= r) {
                    labels.set({i, j, k}, 1);
                    ++count;
                }
    const BranchedGrid grid = make_grid(labels, 2);
    EmbeddedSurface s(grid, 2);
    // How far the surface strays from the best ball through it: the RMS of the radius about its mean.
    auto radius_spread = [&] {
        const SurfaceMesh m = s.mesh(grid);
        double sum = 0.0, sum2 = 0.0;
        for (const Eigen::Vector3d& p : m.positions) {
            const double d = (p - centre).norm();
            sum += d;
            sum2 += d * d;
        }
        const double n = static_cast<double>(m.positions.size());
        return std::sqrt(std::max(0.0, sum2 / n - (sum / n) * (sum / n)));
    };
    const double spread_before = radius_spread();
    const double volume_before = s.rest_volume_mm3(grid);
    const double change = s.smooth_windowed_sinc(grid, 20, 0.05); // the scenes' default
    const double spread_after = radius_spread();
    EXPECT_LT(spread_after, 0.55 * spread_before) << "terraces left: " << spread_before << " -> " << spread_after << " mm";
    EXPECT_LT(std::abs(change), 0.02) << "the filter itself keeps the shape's volume closely";
    EXPECT_NEAR(s.rest_volume_mm3(grid), volume_before, 1e-6 * volume_before) << "and the normal move restores it";
    const double voxels_mm3 = count * spacing.prod();
    EXPECT_NEAR(s.rest_volume_mm3(grid), voxels_mm3, 0.01 * voxels_mm3) << "within 1 % of the voxels' volume";
    expect_closed_oriented(s.mesh(grid));
    // Still embedded: node positions at rest reproduce the smoothed rest surface.
    const auto rest = grid.rest_node_positions(2);
    const SurfaceMesh at_rest = s.mesh(grid), deformed_rest = s.mesh(grid, rest);
    for (std::size_t i = 0; i < at_rest.positions.size(); ++i)
        ASSERT_LT((at_rest.positions[i] - deformed_rest.positions[i]).norm(), 1e-9);
}
