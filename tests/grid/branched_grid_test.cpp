#include "grid/branched_grid.hpp"

#include "core/morton.hpp"
#include "grid/condensation.hpp"
#include "grid/phantom.hpp"

#include <Eigen/Geometry>
#include <gtest/gtest.h>

#include <map>
#include <queue>
#include <random>
#include <set>

using namespace vox;
using namespace vox::grid;

namespace {

const std::vector<ElasticMaterial> k_materials{{lame_from_young_poisson(3e4, 0.45), 1000.0},
                                             {lame_from_young_poisson(1e5, 0.3), 1200.0}};

BranchedGrid build(const LabelGrid& labels, int levels)
{
    return BranchedGrid(FineVoxels(labels, [](std::int32_t label) { return label == 2 ? 1 : 0; }), k_materials,
                        levels, {.level0_nodes = true});
}

LabelGrid from_coords(const std::vector<Coord>& coords, double h = 1.0)
{
    Eigen::Matrix4d t = Eigen::Matrix4d::Identity();
    t.topLeftCorner<3, 3>() *= h;
    LabelGrid g(t);
    for (const Coord& c : coords) g.set(c, 1);
    return g;
}

/// Random blobby object with two materials, some negative indices.
LabelGrid random_object(unsigned seed, int n, double fill)
{
    std::mt19937 rng(seed);
    std::bernoulli_distribution present(fill);
    LabelGrid g(Eigen::Vector4d(0.5, 0.75, 1.25, 1.0).asDiagonal().toDenseMatrix());
    for (int z = -3; z < n - 3; ++z)
        for (int y = 0; y < n; ++y)
            for (int x = -9; x < n - 9; ++x)
                if (present(rng)) g.set({x, y, z}, (x + y) % 3 == 0 ? 2 : 1);
    return g;
}

/// Independent reference: connected components of a cell's voxels by breadth-first search over
/// face neighbours, as sets of voxel coordinates, for every cell at `level` (level < 0: the
/// pieces of the whole object).
std::set<std::set<std::tuple<int, int, int>>> reference_elements(const LabelGrid& g, int level)
{
    std::map<std::tuple<int, int, int>, std::set<std::tuple<int, int, int>>> cells;
    g.for_each_active([&](const Coord& c, std::int32_t) {
        const std::tuple<int, int, int> cell =
            level < 0 ? std::tuple{0, 0, 0} : std::tuple{c.x() >> level, c.y() >> level, c.z() >> level};
        cells[cell].insert({c.x(), c.y(), c.z()});
    });
    std::set<std::set<std::tuple<int, int, int>>> out;
    for (auto& [cell, voxels] : cells) {
        std::set<std::tuple<int, int, int>> left = voxels;
        while (!left.empty()) {
            std::set<std::tuple<int, int, int>> component;
            std::queue<std::tuple<int, int, int>> frontier;
            frontier.push(*left.begin());
            left.erase(left.begin());
            while (!frontier.empty()) {
                auto [x, y, z] = frontier.front();
                frontier.pop();
                component.insert({x, y, z});
                const int d[6][3] = {{1, 0, 0}, {-1, 0, 0}, {0, 1, 0}, {0, -1, 0}, {0, 0, 1}, {0, 0, -1}};
                for (const auto& o : d) {
                    auto it = left.find({x + o[0], y + o[1], z + o[2]});
                    if (it != left.end()) {
                        frontier.push(*it);
                        left.erase(it);
                    }
                }
            }
            out.insert(component);
        }
    }
    return out;
}

std::set<std::set<std::tuple<int, int, int>>> grid_elements(const BranchedGrid& grid, int level)
{
    std::set<std::set<std::tuple<int, int, int>>> out;
    for (const Element& e : grid.level(level).elements) {
        if (!e.alive) continue;
        std::set<std::tuple<int, int, int>> voxels;
        for (std::uint32_t v : e.voxels) {
            const Coord c = grid.voxels().coord(v);
            voxels.insert({c.x(), c.y(), c.z()});
        }
        out.insert(voxels);
    }
    return out;
}

} // namespace

TEST(BranchedGrid, FullBoxHasOneElementPerCellAndSharedNodes)
{
    PhantomSpec s = default_phantom(PhantomShape::block);
    s.size_mm = {8, 4, 4};
    const BranchedGrid grid = build(make_phantom(s), 2);
    EXPECT_EQ(grid.level0_stats().elements, 128u);
    EXPECT_EQ(grid.level0_stats().nodes, 9u * 5u * 5u);
    EXPECT_EQ(grid.level(1).stats.cells, 16u);
    EXPECT_EQ(grid.level(1).stats.elements, 16u);
    EXPECT_EQ(grid.level(1).stats.nodes, 5u * 3u * 3u);
    EXPECT_EQ(grid.level(2).stats.elements, 2u);
    EXPECT_EQ(grid.level(2).stats.nodes, 3u * 2u * 2u);
    EXPECT_EQ(grid.level(2).stats.condensation_steps_direct, 2u); // each cell is one full sub-node
    EXPECT_EQ(grid.level(2).stats.condensation_steps_recursive, 2u * (64u + 8u));
}

TEST(BranchedGrid, UtubeBranchesAtLevelThree)
{
    // The paper's Figure 3: the upper cell holds both legs without the base that joins them.
    const BranchedGrid grid = build(make_phantom(default_phantom(PhantomShape::utube)), 3);
    for (int l = 1; l <= 2; ++l) EXPECT_EQ(grid.level(l).stats.elements, grid.level(l).stats.cells) << l;
    const Level& l3 = grid.level(3);
    EXPECT_EQ(l3.stats.cells, 2u);
    ASSERT_EQ(l3.stats.elements, 3u);
    // Both upper elements hang on the lower one through their own leg: each shares the lower
    // element's top face nodes, so the piece has 8 + 4 + 4 nodes.
    EXPECT_EQ(l3.stats.nodes, 16u);
    const Element& lower = l3.elements[0];
    EXPECT_EQ(lower.cell, Coord(0, 0, 0));
    for (int u = 1; u <= 2; ++u) {
        const Element& upper = l3.elements[static_cast<std::size_t>(u)];
        EXPECT_EQ(upper.cell, Coord(0, 0, 1));
        for (int c = 0; c < 4; ++c) EXPECT_EQ(upper.nodes[c], lower.nodes[c + 4]);
        for (int c = 4; c < 8; ++c) EXPECT_NE(upper.nodes[c], l3.elements[static_cast<std::size_t>(3 - u)].nodes[c]);
    }
}

TEST(BranchedGrid, VoxelsTouchingAlongAnEdgeShareNothing)
{
    const BranchedGrid grid = build(from_coords({{0, 0, 0}, {1, 1, 0}}), 1);
    EXPECT_EQ(grid.level0_stats().nodes, 16u);
    EXPECT_EQ(grid.level(1).stats.cells, 1u);
    EXPECT_EQ(grid.level(1).stats.elements, 2u); // superimposed
    EXPECT_EQ(grid.level(1).stats.nodes, 16u);
    // A third voxel face-connected to both joins them through shared nodes.
    const BranchedGrid joined = build(from_coords({{0, 0, 0}, {1, 1, 0}, {1, 0, 0}}), 1);
    EXPECT_EQ(joined.level(1).stats.elements, 1u);
}

TEST(BranchedGrid, ElementsAreTheConnectedComponentsOfEachCell)
{
    for (unsigned seed : {1u, 2u, 3u}) {
        const LabelGrid g = random_object(seed, 20, 0.55);
        const BranchedGrid grid = build(g, 4);
        for (int l = 1; l <= 4; ++l) {
            SCOPED_TRACE(testing::Message() << "seed " << seed << " level " << l);
            EXPECT_EQ(grid_elements(grid, l), reference_elements(g, l));
        }
    }
}

TEST(BranchedGrid, NodesFollowFaceConnectivityAndNeverJoinPieces)
{
    const LabelGrid g = random_object(7, 16, 0.45);
    const BranchedGrid grid = build(g, 3);
    const auto pieces = reference_elements(g, -1);
    std::map<std::tuple<int, int, int>, int> piece_of;
    int p = 0;
    for (const auto& piece : pieces) {
        for (const auto& v : piece) piece_of[v] = p;
        ++p;
    }
    for (int l = 1; l <= 3; ++l) {
        const Level& lv = grid.level(l);
        std::map<std::uint32_t, int> node_piece;
        for (const Element& e : lv.elements) {
            const Coord c = grid.voxels().coord(e.voxels.front());
            const int piece = piece_of.at({c.x(), c.y(), c.z()});
            for (std::uint32_t n : e.nodes) {
                auto [it, fresh] = node_piece.emplace(n, piece);
                EXPECT_EQ(it->second, piece) << "a node joins two pieces at level " << l;
            }
        }
        // Every connected pair shares exactly the four nodes of the common face.
        for (const Element& a : lv.elements)
            for (const Link& link : a.links) {
                const Element& b = lv.elements[link.element];
                const int axis = link.direction / 2;
                const int side = link.direction & 1;
                EXPECT_EQ((b.cell - a.cell), (side ? 1 : -1) * Coord::Unit(axis));
                for (int c = 0; c < 8; ++c) {
                    if (((c >> axis) & 1) == side) {
                        EXPECT_EQ(a.nodes[c], b.nodes[c ^ (1 << axis)]);
                    }
                }
            }
    }
}

TEST(BranchedGrid, ElementMatricesEqualBruteForceAndMassIsConserved)
{
    const LabelGrid g = random_object(11, 18, 0.6);
    const BranchedGrid grid = build(g, 3);
    const double expect_mass = grid.total_mass_kg();
    for (int l = 1; l <= 3; ++l) {
        const Level& lv = grid.level(l);
        double mass = 0.0;
        for (std::uint32_t e = 0; e < lv.elements.size(); ++e) {
            const Element& el = lv.elements[e];
            const Matrix8d m = grid.mass(l, e);
            mass += m.sum();
            std::vector<CellVoxel> cell;
            for (std::uint32_t v : el.voxels) {
                const Coord local = grid.voxels().coord(v) - (el.cell * (1 << l));
                cell.push_back({morton_encode(local.x(), local.y(), local.z()), grid.voxels().material(v)});
            }
            std::sort(cell.begin(), cell.end());
            const auto brute = condense_brute_force(cell, l, grid.voxels().voxel_size_m(), grid.materials());
            const Matrix24d k = grid.stiffness(l, e);
            EXPECT_LT((k - brute.stiffness).norm(), 1e-10 * brute.stiffness.norm());
            EXPECT_LT((m - brute.mass).norm(), 1e-10 * brute.mass.norm());
        }
        EXPECT_NEAR(mass, expect_mass, 1e-12 * expect_mass) << "level " << l;
    }
}
