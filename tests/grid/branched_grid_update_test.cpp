// Local updates of the branched grid must equal a from-scratch rebuild of what remains: the same
// elements (as voxel sets), the same exact contents, the same node sharing.

#include "grid/branched_grid.hpp"

#include "grid/phantom.hpp"

#include <gtest/gtest.h>

#include <map>
#include <random>
#include <set>

using namespace vox;
using namespace vox::grid;

namespace vox::grid {
// Exact comparison of contents, found by argument-dependent lookup from std::map's operator==.
bool operator==(const MaterialMoments& a, const MaterialMoments& b)
{
    return a.material == b.material && a.voxels == b.voxels && a.moments == b.moments;
}
} // namespace vox::grid

namespace {

const std::vector<ElasticMaterial> k_materials{{lame_from_young_poisson(3e4, 0.45), 1000.0},
                                             {lame_from_young_poisson(1e5, 0.3), 1200.0}};
std::int32_t material_of(std::int32_t label) { return label == 2 ? 1 : 0; }

using VoxelSet = std::vector<std::tuple<int, int, int>>;

/// A level in canonical form: element voxel sets with their exact contents, and the node
/// partition as sets of (element voxel set, corner).
struct Canonical {
    std::map<VoxelSet, ElementContent> elements;
    std::set<std::set<std::pair<VoxelSet, int>>> nodes;
    std::uint64_t cells = 0, element_count = 0, node_count = 0;
};

Canonical canonical(const BranchedGrid& grid, int l)
{
    Canonical out;
    const Level& lv = grid.level(l);
    std::map<std::uint32_t, std::set<std::pair<VoxelSet, int>>> nodes;
    for (const Element& e : lv.elements) {
        if (!e.alive) continue;
        VoxelSet key;
        for (std::uint32_t v : e.voxels) {
            const Coord c = grid.voxels().coord(v);
            key.emplace_back(c.x(), c.y(), c.z());
        }
        std::sort(key.begin(), key.end());
        out.elements[key] = e.content;
        for (int c = 0; c < 8; ++c) nodes[e.nodes[c]].insert({key, c});
    }
    for (auto& [id, members] : nodes) out.nodes.insert(members);
    out.cells = lv.stats.cells;
    out.element_count = lv.stats.elements;
    out.node_count = lv.stats.nodes;
    return out;
}

/// Rebuilds from scratch the voxels that remain in `grid`, with the same disconnected faces.
BranchedGrid rebuild(const BranchedGrid& grid, const std::vector<std::pair<Coord, int>>& disconnected)
{
    LabelGrid labels(grid.voxels().index_to_world());
    for (std::uint32_t v = 0; v < grid.voxels().slots(); ++v)
        if (grid.voxels().alive(v)) labels.set(grid.voxels().coord(v), grid.voxels().label(v));
    FineVoxels fresh(labels, material_of);
    for (const auto& [c, axis] : disconnected) {
        const std::uint32_t v = fresh.find(c);
        if (v != FineVoxels::missing && fresh.find(c + Coord::Unit(axis)) != FineVoxels::missing)
            fresh.disconnect(v, axis);
    }
    return BranchedGrid(std::move(fresh), k_materials, grid.max_level());
}

void expect_equal_to_rebuild(const BranchedGrid& grid, const std::vector<std::pair<Coord, int>>& disconnected)
{
    const BranchedGrid fresh = rebuild(grid, disconnected);
    for (int l = 1; l <= grid.max_level(); ++l) {
        SCOPED_TRACE(testing::Message() << "level " << l);
        const Canonical a = canonical(grid, l), b = canonical(fresh, l);
        EXPECT_EQ(a.cells, b.cells);
        EXPECT_EQ(a.element_count, b.element_count);
        EXPECT_EQ(a.node_count, b.node_count);
        EXPECT_EQ(a.elements.size(), b.elements.size());
        EXPECT_TRUE(a.elements == b.elements);
        EXPECT_TRUE(a.nodes == b.nodes);
        // Element matrices follow from the contents, so they agree exactly too.
    }
}

/// Number of pieces at level l: components of the element graph through shared nodes.
std::size_t pieces(const BranchedGrid& grid, int l)
{
    const Level& lv = grid.level(l);
    std::map<std::uint32_t, std::uint32_t> parent;
    auto find = [&](std::uint32_t x) {
        while (parent[x] != x) x = parent[x] = parent[parent[x]];
        return x;
    };
    for (const Element& e : lv.elements)
        if (e.alive)
            for (std::uint32_t n : e.nodes) parent.emplace(n, n);
    for (const Element& e : lv.elements)
        if (e.alive)
            for (std::uint32_t n : e.nodes) parent[find(n)] = find(e.nodes[0]);
    std::set<std::uint32_t> roots;
    for (auto& [n, p] : parent) roots.insert(find(n));
    return roots.size();
}

} // namespace

TEST(BranchedGridUpdate, RandomRemovalsAndDisconnectionsEqualRebuilds)
{
    std::size_t created = 0, removed_elements = 0, updated = 0;
    for (unsigned seed : {20261122u, 7u, 99u}) {
        SCOPED_TRACE(testing::Message() << "seed " << seed);
        std::mt19937 rng(seed);
        LabelGrid labels(Eigen::Vector4d(0.5, 0.75, 1.25, 1.0).asDiagonal().toDenseMatrix());
        for (int z = -4; z < 12; ++z)
            for (int y = 0; y < 14; ++y)
                for (int x = -6; x < 14; ++x)
                    if (std::bernoulli_distribution(0.8)(rng)) labels.set({x, y, z}, (x + 2 * y) % 5 == 0 ? 2 : 1);
        BranchedGrid grid(FineVoxels(labels, material_of), k_materials, 4);
        std::vector<std::pair<Coord, int>> disconnected;
        std::uniform_int_distribution<int> px(-6, 13), py(0, 13), pz(-4, 11), axis(0, 2);
        for (int batch = 0; batch < 16; ++batch) {
            SCOPED_TRACE(testing::Message() << "batch " << batch);
            std::vector<Coord> removed;
            std::vector<std::pair<Coord, int>> faces;
            const int n = 1 + batch * 7;
            for (int k = 0; k < n; ++k) {
                if (k % 3 == 2)
                    faces.emplace_back(Coord(px(rng), py(rng), pz(rng)), axis(rng));
                else
                    removed.emplace_back(px(rng), py(rng), pz(rng));
            }
            const UpdateReport report = grid.update(removed, faces);
            for (int l = 1; l <= 4; ++l) {
                created += report.levels[l].created.size();
                removed_elements += report.levels[l].removed.size();
                updated += report.levels[l].updated.size();
            }
            disconnected.insert(disconnected.end(), faces.begin(), faces.end());
            expect_equal_to_rebuild(grid, disconnected);
        }
    }
    // Every kind of change happened: splits and removals (created, removed) and plain updates.
    EXPECT_GT(created, 50u);
    EXPECT_GT(removed_elements, 50u);
    EXPECT_GT(updated, 50u);
}

TEST(BranchedGridUpdate, CuttingABeamThroughLeavesTwoPieces)
{
    PhantomSpec s = default_phantom(PhantomShape::beam);
    s.size_mm = {32, 4, 4};
    BranchedGrid grid(FineVoxels(make_phantom(s), material_of), k_materials, 3);
    ASSERT_EQ(pieces(grid, 3), 1u);
    std::vector<Coord> slab;
    for (int z = 0; z < 4; ++z)
        for (int y = 0; y < 4; ++y) slab.emplace_back(13, y, z);
    const UpdateReport report = grid.update(slab, {});
    for (int l = 1; l <= 3; ++l) EXPECT_EQ(pieces(grid, l), 2u) << "level " << l;
    // Level 3 cell x in [8, 16) now holds two pieces: it split into two superimposed elements,
    // each of which came from the one old element.
    const LevelChange& l3 = report.levels[3];
    ASSERT_EQ(l3.created.size(), 2u);
    ASSERT_EQ(l3.removed.size(), 1u);
    for (const auto& [id, from] : l3.created) EXPECT_EQ(from, std::vector<std::uint32_t>{l3.removed[0]});
    expect_equal_to_rebuild(grid, {});
}

TEST(BranchedGridUpdate, SeparatingFacesSplitsWithoutLosingVoxels)
{
    PhantomSpec s = default_phantom(PhantomShape::beam);
    s.size_mm = {16, 4, 4};
    BranchedGrid grid(FineVoxels(make_phantom(s), material_of), k_materials, 3);
    std::vector<std::pair<Coord, int>> faces;
    for (int z = 0; z < 4; ++z)
        for (int y = 0; y < 4; ++y) faces.emplace_back(Coord(5, y, z), 0);
    grid.update({}, faces);
    EXPECT_EQ(grid.voxels().alive_count(), 256u);
    for (int l = 1; l <= 3; ++l) EXPECT_EQ(pieces(grid, l), 2u) << "level " << l;
    EXPECT_EQ(grid.level(3).stats.elements, 3u); // cell [0, 8) holds both sides of the cut
    expect_equal_to_rebuild(grid, faces);
}

TEST(BranchedGridUpdate, RemovingTheUtubeBaseSeparatesTheLegs)
{
    BranchedGrid grid(FineVoxels(make_phantom(default_phantom(PhantomShape::utube)), material_of), k_materials, 3);
    ASSERT_EQ(pieces(grid, 3), 1u);
    std::vector<Coord> base;
    for (int z = 0; z < 3; ++z)
        for (int y = 0; y < 3; ++y)
            for (int x = 3; x < 5; ++x) base.emplace_back(x, y, z); // the base under the gap
    grid.update(base, {});
    EXPECT_EQ(pieces(grid, 3), 2u);
    EXPECT_EQ(grid.level(3).stats.elements, 4u); // both cells now hold two legs each
    expect_equal_to_rebuild(grid, {});
    // Removing everything removes every element and node.
    std::vector<Coord> all;
    for (int z = 0; z < 16; ++z)
        for (int y = 0; y < 3; ++y)
            for (int x = 0; x < 8; ++x) all.emplace_back(x, y, z);
    grid.update(all, {});
    for (int l = 1; l <= 3; ++l) {
        EXPECT_EQ(grid.level(l).stats.elements, 0u);
        EXPECT_EQ(grid.level(l).stats.cells, 0u);
        EXPECT_EQ(grid.level(l).stats.nodes, 0u);
    }
}
