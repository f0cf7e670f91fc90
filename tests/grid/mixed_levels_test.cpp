// Two levels in one model (grid/mixed_levels.hpp): every voxel in exactly one element and the
// mass that of the whole grid; ties that reproduce an affine field exactly; no crack along the
// border (the fine side's field equals the coarse element's on every shared face, for any nodal
// values); and of a coarse cell's superimposed elements, a border node follows the one whose
// material it connects to.

#include "grid/mixed_levels.hpp"

#include "grid/hex8.hpp"
#include "grid/phantom.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <map>
#include <random>
#include <set>

using namespace vox;
using namespace vox::grid;

namespace {

const std::vector<ElasticMaterial> k_soft{{lame_from_young_poisson(3e4, 0.45), 1000.0}};

/// A random blob (some negative indices) and a region: the coarse cells whose centre lies within
/// `radius` voxels of `centre`.
BranchedGrid blob(unsigned seed, int n)
{
    std::mt19937 rng(seed);
    std::uniform_real_distribution<double> u(0.0, 1.0);
    LabelGrid g;
    const Eigen::Vector3d c(0.5 * n - 3, 0.5 * n, 0.5 * n);
    for (int i = -3; i < n - 3; ++i)
        for (int j = 0; j < n; ++j)
            for (int k = 0; k < n; ++k) {
                const double r = (Eigen::Vector3d(i, j, k) - c).norm() / (0.5 * n);
                if (r < 0.8 + 0.25 * u(rng)) g.set({i, j, k}, 1);
            }
    return BranchedGrid(FineVoxels(g, [](std::int32_t) { return 0; }), k_soft, 3);
}

std::function<bool(std::uint32_t)> near(const BranchedGrid& grid, int level, const Eigen::Vector3d& centre, double radius)
{
    return [&grid, level, centre, radius](std::uint32_t e) {
        const Coord& cell = grid.level(level).elements[e].cell;
        const Eigen::Vector3d middle = (cell.cast<double>() + Eigen::Vector3d::Constant(0.5)) * (1 << level) - Eigen::Vector3d::Constant(0.5);
        return (middle - centre).norm() < radius;
    };
}

/// Index-space position (voxel units) of corner c of grid element e of `level`.
Eigen::Vector3d corner_index(const BranchedGrid& grid, int level, std::uint32_t e, int c)
{
    return BranchedGrid::cell_corner_index(grid.level(level).elements[e].cell, level, c);
}

/// The trilinear field of element `el` (values per mixed node in `u`) at index-space point p.
Eigen::Vector3d field(const BranchedGrid& grid, const MixedLevels::Element& el, const std::vector<Eigen::Vector3d>& u, const Eigen::Vector3d& p)
{
    const Eigen::Vector3d t = (p - corner_index(grid, el.level, el.element, 0)) / static_cast<double>(1 << el.level);
    Eigen::Vector3d out = Eigen::Vector3d::Zero();
    for (int c = 0; c < 8; ++c) out += hex8_shape(c, t) * u[el.nodes[static_cast<std::size_t>(c)]];
    return out;
}

/// Values at every mixed node: `free` at the untied ones, the ties' combinations at the others.
std::vector<Eigen::Vector3d> expand(const MixedLevels& m, std::vector<Eigen::Vector3d> u)
{
    for (const MixedLevels::Tie& t : m.ties()) {
        Eigen::Vector3d v = Eigen::Vector3d::Zero();
        for (int c = 0; c < 8; ++c) v += t.weights[static_cast<std::size_t>(c)] * u[t.masters[static_cast<std::size_t>(c)]];
        u[t.node] = v;
    }
    return u;
}

TEST(MixedLevels, EveryVoxelIsInOneElementAndTheMassIsTheWholeGrids)
{
    for (unsigned seed : {1u, 2u, 3u}) {
        const BranchedGrid grid = blob(seed, 28);
        for (const auto& [fine, coarse] : {std::pair{1, 3}, std::pair{2, 3}, std::pair{1, 2}}) {
            const MixedLevels m(grid, fine, coarse, near(grid, coarse, Eigen::Vector3d(6, 10, 12), 9.0));
            ASSERT_GT(m.fine_elements(), 0u);
            ASSERT_GT(m.coarse_elements(), 0u);
            std::vector<int> seen(grid.voxels().slots(), 0);
            double mass = 0.0;
            for (const MixedLevels::Element& el : m.elements()) {
                for (std::uint32_t v : grid.level(el.level).elements[el.element].voxels) ++seen[v];
                mass += grid.mass(el.level, el.element).sum();
            }
            for (std::uint32_t v = 0; v < grid.voxels().slots(); ++v)
                if (grid.voxels().alive(v)) ASSERT_EQ(seen[v], 1) << "voxel " << v << ", levels " << fine << "/" << coarse;
            EXPECT_NEAR(mass, grid.total_mass_kg(), 1e-12 * grid.total_mass_kg()) << "levels " << fine << "/" << coarse;
        }
    }
}

TEST(MixedLevels, TiesReproduceAnAffineFieldAndLeaveNoCrackAlongTheBorder)
{
    const BranchedGrid grid = blob(7, 28);
    const MixedLevels m(grid, 1, 3, near(grid, 3, Eigen::Vector3d(6, 10, 12), 9.0));
    ASSERT_GT(m.ties().size(), 10u);
    // Rest positions in index space, from the elements' corners (not from the ties).
    std::vector<Eigen::Vector3d> at(m.node_count());
    for (const MixedLevels::Element& el : m.elements())
        for (int c = 0; c < 8; ++c) at[el.nodes[static_cast<std::size_t>(c)]] = corner_index(grid, el.level, el.element, c);
    const Eigen::Matrix3d A = Eigen::Matrix3d::Random();
    const Eigen::Vector3d b = Eigen::Vector3d::Random();
    std::vector<Eigen::Vector3d> affine(m.node_count());
    for (std::size_t n = 0; n < affine.size(); ++n) affine[n] = A * at[n] + b;
    const std::vector<Eigen::Vector3d> tied = expand(m, affine);
    for (const MixedLevels::Tie& t : m.ties()) EXPECT_LT((tied[t.node] - affine[t.node]).norm(), 1e-12);

    // Any values: on each face a region element shares with the outside (its four corners tied to
    // one coarse element), the fine field equals that coarse element's at every point of the face.
    std::mt19937 rng(3);
    std::uniform_real_distribution<double> u(-1.0, 1.0);
    std::vector<Eigen::Vector3d> any(m.node_count());
    for (Eigen::Vector3d& v : any) v = Eigen::Vector3d(u(rng), u(rng), u(rng));
    any = expand(m, any);
    std::vector<const MixedLevels::Tie*> tie_of(m.node_count(), nullptr);
    for (const MixedLevels::Tie& t : m.ties()) tie_of[t.node] = &t;
    std::size_t faces = 0;
    for (std::size_t i = 0; i < m.fine_elements(); ++i) {
        const MixedLevels::Element& el = m.elements()[i];
        for (int axis = 0; axis < 3; ++axis)
            for (int side = 0; side < 2; ++side) {
                std::array<int, 4> face{};
                int k = 0;
                for (int c = 0; c < 8; ++c)
                    if (((c >> axis) & 1) == side) face[static_cast<std::size_t>(k++)] = c;
                const MixedLevels::Tie* first = tie_of[el.nodes[static_cast<std::size_t>(face[0])]];
                bool shared = first != nullptr;
                for (int c : face) {
                    const MixedLevels::Tie* t = tie_of[el.nodes[static_cast<std::size_t>(c)]];
                    shared = shared && t && t->coarse_element == first->coarse_element;
                }
                if (!shared) continue;
                ++faces;
                const auto coarse = std::find_if(m.elements().begin(), m.elements().end(), [&](const MixedLevels::Element& e) {
                    return e.level == 3 && e.element == first->coarse_element;
                });
                ASSERT_NE(coarse, m.elements().end());
                for (int s = 0; s < 5; ++s) {
                    Eigen::Vector3d t(u(rng) * 0.5 + 0.5, u(rng) * 0.5 + 0.5, u(rng) * 0.5 + 0.5);
                    t[axis] = side;
                    const Eigen::Vector3d p = corner_index(grid, 1, el.element, 0) + 2.0 * t;
                    EXPECT_LT((field(grid, el, any, p) - field(grid, *coarse, any, p)).norm(), 1e-12) << "a crack at " << p.transpose();
                }
            }
    }
    EXPECT_GT(faces, 10u);
}

TEST(MixedLevels, ABorderNodeFollowsTheSuperimposedElementWhoseMaterialItConnectsTo)
{
    // A U of 1 mm voxels, 8 wide (arms x < 3 and x >= 5), 16 high, base z < 3: at level 3 the top
    // cell (z 8 - 15) holds the two arms as two superimposed elements. The bottom cell refined to
    // level 1: the border is the plane between the two cells, crossed by both arms.
    PhantomSpec u = default_phantom(PhantomShape::utube);
    const BranchedGrid grid(FineVoxels(make_phantom(u), [](std::int32_t) { return 0; }), k_soft, 3);
    const Level& l3 = grid.level(3);
    const MixedLevels m(grid, 1, 3, [&](std::uint32_t e) { return l3.elements[e].cell.z() == 0; });
    ASSERT_EQ(m.coarse_elements(), 2u) << "the two arms above";
    std::map<std::uint32_t, int> per_arm;
    // The arm (left: x < 3, right: x >= 5) of the voxels of a grid element.
    auto arm = [&](int level, std::uint32_t e) {
        std::set<int> sides;
        for (std::uint32_t v : grid.level(level).elements[e].voxels) sides.insert(grid.voxels().coord(v).x() < 3 ? 0 : 1);
        return sides;
    };
    for (const MixedLevels::Tie& t : m.ties()) {
        const std::set<int> followed = arm(3, t.coarse_element);
        ASSERT_EQ(followed.size(), 1u) << "a top cell element holds one arm";
        // The fine elements of the region using the node hold material of that arm only, where it
        // rises into the coarse cell above (the base, below z = 3, holds both arms' ends).
        for (std::size_t i = 0; i < m.fine_elements(); ++i) {
            const MixedLevels::Element& el = m.elements()[i];
            if (std::find(el.nodes.begin(), el.nodes.end(), t.node) == el.nodes.end()) continue;
            if (grid.level(1).elements[el.element].cell.z() < 2) continue; // the base
            EXPECT_EQ(arm(1, el.element), followed) << "node at " << m.rest_positions_mm()[t.node].transpose() << " follows the other arm";
        }
        ++per_arm[t.coarse_element];
        // Its masters are that element's corners only.
        for (int c = 0; c < 8; ++c)
            if (t.weights[static_cast<std::size_t>(c)] != 0.0)
                EXPECT_EQ(m.node_level(t.masters[static_cast<std::size_t>(c)]), 3);
    }
    EXPECT_EQ(per_arm.size(), 2u) << "both arms hold border nodes";
}

} // namespace
