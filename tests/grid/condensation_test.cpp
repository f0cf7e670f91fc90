#include "grid/condensation.hpp"
#include "grid/element_moments.hpp"

#include "core/morton.hpp"

#include <Eigen/Geometry>
#include <gtest/gtest.h>

#include <algorithm>
#include <random>

using namespace vox;
using namespace vox::grid;

namespace {

const Eigen::Vector3d k_voxel(0.617188e-3, 0.617188e-3, 1.33333e-3); // the liver's spacing, m
const std::vector<ElasticMaterial> k_materials{{lame_from_young_poisson(3e4, 0.45), 1060.0},
                                             {lame_from_young_poisson(1e5, 0.3), 1200.0}};

/// A random voxel set of a level-L cell: each voxel present with probability `fill`; material 1
/// in the half x >= n/2 when `two_materials`, else 0.
std::vector<CellVoxel> random_cell(int level, double fill, bool two_materials, unsigned seed)
{
    std::mt19937 rng(seed);
    std::bernoulli_distribution present(fill);
    const int n = 1 << level;
    std::vector<CellVoxel> v;
    for (int z = 0; z < n; ++z)
        for (int y = 0; y < n; ++y)
            for (int x = 0; x < n; ++x)
                if (present(rng)) v.push_back({morton_encode(x, y, z), (two_materials && 2 * x >= n) ? 1 : 0});
    std::sort(v.begin(), v.end());
    return v;
}

double relative(const Matrix24d& a, const Matrix24d& b) { return (a - b).norm() / b.norm(); }
double relative(const Matrix8d& a, const Matrix8d& b) { return (a - b).norm() / b.norm(); }

/// Counts maximal full one-material octree nodes by building the octree explicitly (a second,
/// independent route to the direct step count).
std::uint64_t count_full_nodes(const std::vector<CellVoxel>& v, std::uint64_t first, int level)
{
    const std::uint64_t size = std::uint64_t{1} << (3 * level);
    auto lo = std::lower_bound(v.begin(), v.end(), CellVoxel{first, 0});
    auto hi = std::lower_bound(v.begin(), v.end(), CellVoxel{first + size, 0});
    if (lo == hi) return 0;
    const bool one_material = std::all_of(lo, hi, [&](const CellVoxel& c) { return c.material == lo->material; });
    if (static_cast<std::uint64_t>(hi - lo) == size && one_material) return 1;
    std::uint64_t n = 0;
    for (int child = 0; child < 8; ++child) n += count_full_nodes(v, first + child * (size / 8), level - 1);
    return n;
}

} // namespace

TEST(Condensation, ThePapersQuadtreeExampleCounts10DirectAnd67RecursiveSteps)
{
    // Figure 6: a level-3 quadtree cell holding the intervals [0-31] [33] [36-37] [39] [48-55]
    // [57] [60-63]; the paper finds 10 full nodes, against 49 + 14 + 4 = 67 recursive steps.
    std::vector<CellVoxel> v;
    auto add = [&](std::uint64_t first, std::uint64_t last) {
        for (std::uint64_t c = first; c <= last; ++c) v.push_back({c, 0});
    };
    add(0, 31), add(33, 33), add(36, 37), add(39, 39), add(48, 55), add(57, 57), add(60, 63);
    const auto nodes = full_subnodes(v, 3, 2);
    ASSERT_EQ(nodes.size(), 10u);
    const std::vector<std::pair<std::uint64_t, int>> expect{{0, 2},  {16, 2}, {33, 0}, {36, 0}, {37, 0},
                                                            {39, 0}, {48, 1}, {52, 1}, {57, 0}, {60, 1}};
    for (std::size_t i = 0; i < nodes.size(); ++i) {
        EXPECT_EQ(nodes[i].first, expect[i].first);
        EXPECT_EQ(nodes[i].level, expect[i].second);
    }
    EXPECT_EQ(recursive_step_count(v, 3, 2), 67u);
}

TEST(Condensation, FullCellIsOneDirectStepAndScalesAsThePaperSays)
{
    for (int level = 1; level <= 3; ++level) {
        const auto v = random_cell(level, 1.0, false, 1);
        const auto direct = condense_direct(v, level, k_voxel, k_materials);
        EXPECT_EQ(direct.steps, 1u);
        // Equations 2 and 3: K_l = 2^l K_0, M_l = 2^(3l) M_0 for the same element shape.
        const double s = 1 << level;
        EXPECT_LT(relative(direct.stiffness, s * hex8_stiffness(k_voxel, k_materials[0].lame)), 1e-12);
        EXPECT_LT(relative(direct.mass, s * s * s * hex8_mass(k_voxel, k_materials[0].density_kg_m3)), 1e-12);
        std::uint64_t recursive = 0;
        for (int l = 0; l < level; ++l) recursive += std::uint64_t{1} << (3 * (level - l));
        EXPECT_EQ(recursive_step_count(v, level), recursive);
    }
}

TEST(Condensation, DirectRecursiveBruteForceAndMomentsAgreeOnRandomCells)
{
    for (int level = 1; level <= 3; ++level)
        for (double fill : {0.1, 0.6, 0.95})
            for (bool two : {false, true}) {
                SCOPED_TRACE(testing::Message() << "level " << level << " fill " << fill << " two materials " << two);
                const auto v = random_cell(level, fill, two, 17u * level + static_cast<unsigned>(fill * 100) + two);
                if (v.empty()) continue;
                const auto direct = condense_direct(v, level, k_voxel, k_materials);
                const auto recursive = condense_recursive(v, level, k_voxel, k_materials);
                const auto brute = condense_brute_force(v, level, k_voxel, k_materials);
                EXPECT_LT(relative(direct.stiffness, brute.stiffness), 1e-10);
                EXPECT_LT(relative(recursive.stiffness, brute.stiffness), 1e-10);
                EXPECT_LT(relative(direct.mass, brute.mass), 1e-10);
                EXPECT_LT(relative(recursive.mass, brute.mass), 1e-10);
                EXPECT_EQ(brute.steps, v.size());
                EXPECT_EQ(recursive.steps, recursive_step_count(v, level));
                EXPECT_EQ(direct.steps, count_full_nodes(v, 0, level));
                EXPECT_LE(direct.steps, brute.steps);

                ElementContent content;
                for (const CellVoxel& c : v)
                    update_content(content, c.material,
                                   {int(morton_decode_axis(c.morton, 0)), int(morton_decode_axis(c.morton, 1)),
                                    int(morton_decode_axis(c.morton, 2))},
                                   +1);
                const MomentMatrices maps(level, k_voxel);
                EXPECT_LT(relative(maps.stiffness(content, k_materials), brute.stiffness), 1e-10);
                EXPECT_LT(relative(maps.mass(content, k_materials), brute.mass), 1e-10);

                // Total mass = sum over voxels of density x voxel volume.
                double expect = 0.0;
                for (const CellVoxel& c : v) expect += k_materials[c.material].density_kg_m3 * k_voxel.prod();
                EXPECT_NEAR(direct.mass.sum(), expect, 1e-12 * expect);
            }
}

TEST(Condensation, CondensedStiffnessAnnihilatesRigidMotions)
{
    const auto v = random_cell(3, 0.4, true, 5);
    const Matrix24d k = condense_direct(v, 3, k_voxel, k_materials).stiffness;
    const Eigen::Vector3d cell = 8.0 * k_voxel;
    for (int axis = 0; axis < 3; ++axis) {
        Vector24d t = Vector24d::Zero(), r = Vector24d::Zero();
        Eigen::Vector3d w = Eigen::Vector3d::Zero();
        w[axis] = 1.0;
        for (int c = 0; c < 8; ++c) {
            t[3 * c + axis] = 1.0;
            const Eigen::Vector3d x(cell.x() * (c & 1), cell.y() * ((c >> 1) & 1), cell.z() * ((c >> 2) & 1));
            r.segment<3>(3 * c) = w.cross(x);
        }
        EXPECT_LT((k * t).norm(), 1e-12 * k.norm());
        EXPECT_LT((k * r).norm(), 1e-12 * k.norm() * cell.norm());
    }
}

TEST(Condensation, BoxMomentsEqualSumsOfVoxelMoments)
{
    Moments box{}, sum{};
    add_box_moments(box, {8, 16, 24}, 8);
    for (int z = 24; z < 32; ++z)
        for (int y = 16; y < 24; ++y)
            for (int x = 8; x < 16; ++x) add_voxel_moments(sum, {x, y, z});
    EXPECT_EQ(box, sum);
    // The largest cell (64 voxels per axis) stays within 64 bits.
    Moments full{};
    add_box_moments(full, {0, 0, 0}, 64);
    EXPECT_GT(full[26], 0);
}
