// A cut rebuilds the model without restarting the simulation: every new node takes the position
// and velocity of the material point it sits on, every new element its source's water and
// plastic strain. Checked against fields given as functions of the rest position, across a cut
// that splits coarse cells into superimposed elements.

#include "cut/state_transfer.hpp"

#include "fem/block_grid.hpp"

#include <gtest/gtest.h>

using namespace vox;

namespace {

Eigen::Vector3d position_field(const Eigen::Vector3d& X)
{
    return X + Eigen::Vector3d(0.01 * X.z(), -0.02 * X.x(), 0.03 * X.y() + 1e-4);
}
Eigen::Vector3d velocity_field(const Eigen::Vector3d& X) { return Eigen::Vector3d(1, 2, 3) + 50.0 * X; }
/// A per-cell value: the cell centre's x in mm, so split halves inherit the same value.
double cell_value(const fem::HexModel& m, const fem::HexElement& el)
{
    Eigen::Vector3d centre = Eigen::Vector3d::Zero();
    for (std::uint32_t n : el.dof_node) centre += m.rest_positions()[n] / 8.0;
    return 1e3 * centre.x();
}

class StateTransfer : public ::testing::TestWithParam<int> {};

} // namespace

TEST_P(StateTransfer, NodesAndElementsInheritWhatTheCutDidNotChange)
{
    const int level = GetParam();
    grid::BranchedGrid grid = test::block_grid({8, 4, 4}, level);
    const auto old_model = std::make_unique<fem::HexModel>(grid, level);
    fem::SolverOptions o;
    auto old_solver = std::make_unique<fem::ImplicitSolver>(*old_model, o);
    fem::MaterialBehaviour plastic;
    plastic.yield_strain = 0.01;
    plastic.creep_per_s = 1.0;
    plastic.max_strain = 1.0;
    old_solver->set_materials({plastic});
    for (std::uint32_t n = 0; n < old_model->node_count(); ++n) {
        old_solver->positions()[n] = position_field(old_model->rest_positions()[n]);
        old_solver->velocities()[n] = velocity_field(old_model->rest_positions()[n]);
    }
    for (std::uint32_t e = 0; e < old_model->elements().size(); ++e) {
        const double value = cell_value(*old_model, old_model->elements()[e]);
        old_solver->set_water(e, value / 10.0);
        old_solver->set_plastic_strain(e, value * Eigen::Matrix3d::Identity());
    }
    // Open every face between voxel columns x = 4 and x = 5: inside a level-1 cell (it splits into
    // two superimposed elements) and inside the level-2 cells.
    std::vector<std::pair<grid::Coord, int>> faces;
    for (int y = 0; y < 4; ++y)
        for (int z = 0; z < 4; ++z) faces.emplace_back(grid::Coord(4, y, z), 0);
    const grid::UpdateReport report = grid.update({}, faces);
    const fem::HexModel new_model(grid, level);
    ASSERT_GT(new_model.node_count(), old_model->node_count()); // the split nodes doubled
    fem::ImplicitSolver new_solver(new_model, o);
    new_solver.set_materials({plastic});
    cut::transfer_state(report, *old_model, *old_solver, new_model, new_solver);
    for (std::uint32_t n = 0; n < new_model.node_count(); ++n) {
        const Eigen::Vector3d X = new_model.rest_positions()[n];
        EXPECT_LT((new_solver.positions()[n] - position_field(X)).norm(), 1e-15) << n;
        EXPECT_LT((new_solver.velocities()[n] - velocity_field(X)).norm(), 1e-12) << n;
    }
    for (std::uint32_t e = 0; e < new_model.elements().size(); ++e) {
        const double value = cell_value(new_model, new_model.elements()[e]);
        EXPECT_NEAR(new_solver.water(e), std::min(1.0, value / 10.0), 1e-12) << e;
        EXPECT_NEAR(new_solver.plastic_strain(e)(0, 0), value, 1e-12) << e;
    }
}

TEST_P(StateTransfer, AModelRebuiltFromTheOldOneEqualsAFreshOne)
{
    // Unchanged elements keep their matrices; the result must be the model built from scratch.
    const int level = GetParam();
    grid::BranchedGrid grid = test::block_grid({8, 4, 4}, level);
    const fem::HexModel before(grid, level);
    std::vector<std::pair<grid::Coord, int>> faces;
    for (int y = 0; y < 4; ++y)
        for (int z = 0; z < 4; ++z) faces.emplace_back(grid::Coord(4, y, z), 0);
    const std::vector<grid::Coord> removed{grid::Coord(7, 3, 3), grid::Coord(0, 0, 0)};
    const grid::UpdateReport report = grid.update(removed, faces);
    std::vector<unsigned char> changed(grid.level(level).elements.size(), 0);
    for (const auto& [e, from] : report.levels[static_cast<std::size_t>(level)].created) changed[e] = 1;
    for (std::uint32_t e : report.levels[static_cast<std::size_t>(level)].updated) changed[e] = 1;
    const fem::HexModel fresh(grid, level), reused(grid, level, before, changed);
    ASSERT_EQ(fresh.elements().size(), reused.elements().size());
    ASSERT_EQ(fresh.node_count(), reused.node_count());
    // The same elements on the same grid nodes (numbered apart: the reused model keeps the old order).
    for (std::size_t e = 0; e < fresh.elements().size(); ++e) {
        const fem::HexElement &a = fresh.elements()[e], &b = reused.elements()[e];
        EXPECT_EQ(a.grid_element, b.grid_element);
        for (int c = 0; c < 8; ++c) EXPECT_EQ(fresh.grid_node()[a.dof_node[c]], reused.grid_node()[b.dof_node[c]]) << e;
        EXPECT_EQ(*a.stiffness, *b.stiffness) << e;
        EXPECT_EQ(a.mass, b.mass) << e;
    }
    for (std::size_t n = 0; n < fresh.node_count(); ++n)
        EXPECT_EQ(fresh.nodal_mass()[n], reused.nodal_mass()[reused.dense_node()[fresh.grid_node()[n]]]) << n;
    // The nodes of the model before that are still in use come first, in their old order, so that a
    // preconditioner's factor goes on over them.
    std::uint32_t next = 0;
    for (std::uint32_t g : before.grid_node()) {
        const std::uint32_t now = g < reused.dense_node().size() ? reused.dense_node()[g] : grid::no_index;
        if (now != grid::no_index) EXPECT_EQ(now, next++);
    }
    EXPECT_GT(next, 0u);
}

INSTANTIATE_TEST_SUITE_P(Levels, StateTransfer, ::testing::Values(1, 2));

namespace {

/// The two-level selection of a 16 x 8 x 8 block (level-3 cells 8 voxels wide: two of them along
/// x) refining the coarse cell at x index `cell`.
grid::MixedLevels refining(const grid::BranchedGrid& grid, int cell)
{
    return grid::MixedLevels(grid, 1, 3, [&](std::uint32_t e) { return grid.level(3).elements[e].cell.x() == cell; });
}

void set_fields(const fem::HexModel& model, fem::ImplicitSolver& solver)
{
    for (std::uint32_t n = 0; n < model.node_count(); ++n) {
        solver.positions()[n] = position_field(model.rest_positions()[n]);
        solver.velocities()[n] = velocity_field(model.rest_positions()[n]);
    }
}

void expect_fields(const fem::HexModel& model, const fem::ImplicitSolver& solver)
{
    for (std::uint32_t n = 0; n < model.node_count(); ++n) {
        const Eigen::Vector3d X = model.rest_positions()[n];
        EXPECT_LT((solver.positions()[n] - position_field(X)).norm(), 1e-15) << n;
        EXPECT_LT((solver.velocities()[n] - velocity_field(X)).norm(), 1e-12) << n;
    }
}

} // namespace

TEST(StateTransferTwoLevels, AnAffineStateCarriesOverExactlyAsTheFineRegionMoves)
{
    // The fine region moves from one coarse cell to the other, then the model goes to one level:
    // the state is affine, so every node, fine, coarse or tied, must land on it exactly, and an
    // element's water is the mean over its voxels of the old elements' water.
    const grid::BranchedGrid grid = test::block_grid({16, 8, 8}, 3);
    const grid::MixedLevels left = refining(grid, 0), right = refining(grid, 1);
    const fem::HexModel a(grid, left), b(grid, right), one(grid, 2);
    ASSERT_FALSE(a.ties().empty());
    fem::SolverOptions o;
    fem::ImplicitSolver sa(a, o), sb(b, o), s_one(one, o);
    set_fields(a, sa);
    for (std::uint32_t e = 0; e < a.elements().size(); ++e) sa.set_water(e, a.elements()[e].level == 1 ? 0.2 : 0.6);
    cut::transfer_between_levels(grid, a, sa, b, sb);
    expect_fields(b, sb);
    for (std::uint32_t e = 0; e < b.elements().size(); ++e) {
        const fem::HexElement& el = b.elements()[e];
        const double x_mm = 1e3 * el.centroid.x(); // the left cell (x < 7.5 mm) was fine, the right one coarse
        EXPECT_NEAR(sb.water(e), x_mm < 7.5 ? 0.2 : 0.6, 1e-12) << e;
    }
    cut::transfer_between_levels(grid, b, sb, one, s_one);
    expect_fields(one, s_one);
}

TEST(StateTransferTwoLevels, ACutOnTwoLevelsCarriesTheStateOver)
{
    // Faces opened across both cells (inside the fine region and inside the coarse one); the
    // model rebuilt on the same region takes the old state corner by corner.
    grid::BranchedGrid grid = test::block_grid({16, 8, 8}, 3);
    const grid::MixedLevels before = refining(grid, 0);
    const fem::HexModel old_model(grid, before);
    fem::SolverOptions o;
    fem::ImplicitSolver old_solver(old_model, o);
    set_fields(old_model, old_solver);
    std::vector<std::pair<grid::Coord, int>> faces;
    for (int x = 0; x < 16; ++x)
        for (int y = 0; y < 5; ++y) faces.emplace_back(grid::Coord(x, y, 4), 2);
    const grid::UpdateReport report = grid.update({}, faces);
    const grid::MixedLevels after = refining(grid, 0);
    const fem::HexModel new_model(grid, after);
    ASSERT_GT(new_model.node_count(), old_model.node_count()); // split nodes on both levels
    fem::ImplicitSolver new_solver(new_model, o);
    cut::transfer_state(report, old_model, old_solver, new_model, new_solver);
    expect_fields(new_model, new_solver);
}

TEST(StateTransferTwoLevels, AModelRebuiltFromTheOldOneEqualsAFreshOne)
{
    // The fine region moved, then a cut: elements kept from the model before must carry the same
    // matrices as those a fresh build evaluates.
    grid::BranchedGrid grid = test::block_grid({16, 8, 8}, 3);
    const fem::HexModel left(grid, refining(grid, 0));
    const grid::MixedLevels right_cells = refining(grid, 1);
    const fem::HexModel moved(grid, right_cells, &left), fresh(grid, right_cells);
    const auto same = [](const fem::HexModel& a, const fem::HexModel& b) {
        ASSERT_EQ(a.elements().size(), b.elements().size());
        for (std::size_t e = 0; e < a.elements().size(); ++e) {
            const fem::HexElement &x = a.elements()[e], &y = b.elements()[e];
            EXPECT_EQ(x.level, y.level);
            EXPECT_EQ(x.grid_element, y.grid_element);
            EXPECT_EQ(*x.stiffness, *y.stiffness) << e;
            EXPECT_EQ(x.mass, y.mass) << e;
        }
        EXPECT_EQ(a.nodal_mass(), b.nodal_mass());
    };
    same(moved, fresh);
    // A slit through both cells: the elements it touched are evaluated again, the others kept.
    std::vector<std::pair<grid::Coord, int>> faces;
    for (int x = 0; x < 16; ++x)
        for (int y = 0; y < 5; ++y) faces.emplace_back(grid::Coord(x, y, 4), 2);
    const grid::UpdateReport report = grid.update({}, faces);
    std::array<std::vector<unsigned char>, 2> changed;
    for (int k = 0; k < 2; ++k) {
        const int level = k == 0 ? 1 : 3;
        changed[k].assign(grid.level(level).elements.size(), 0);
        for (const auto& [e, from] : report.levels[static_cast<std::size_t>(level)].created) changed[k][e] = 1;
        for (std::uint32_t e : report.levels[static_cast<std::size_t>(level)].updated) changed[k][e] = 1;
    }
    const grid::MixedLevels cut_cells = refining(grid, 1);
    const fem::HexModel reused(grid, cut_cells, &fresh, {&changed[0], &changed[1]}), rebuilt(grid, cut_cells);
    same(reused, rebuilt);
}

TEST(StateTransferTwoLevels, NodesBothModelsHaveKeepTheirStateAsItIs)
{
    // Any state, not only an affine one: a node on the same grid node of the same level in both
    // models keeps its position and velocity exactly (unless it is now tied, then it follows its
    // coarse nodes), whatever the fine region did elsewhere.
    // Three level-3 cells along x: the region moves from cells 0 and 1 to cells 1 and 2.
    const grid::BranchedGrid grid = test::block_grid({24, 8, 8}, 3);
    const auto cells = [&](int lo, int hi) {
        return grid::MixedLevels(grid, 1, 3, [&, lo, hi](std::uint32_t e) {
            const int x = grid.level(3).elements[e].cell.x();
            return x >= lo && x <= hi;
        });
    };
    const fem::HexModel a(grid, cells(0, 1)), b(grid, cells(1, 2));
    fem::SolverOptions o;
    fem::ImplicitSolver sa(a, o), sb(b, o);
    for (std::uint32_t n = 0; n < a.node_count(); ++n) {
        sa.positions()[n] = a.rest_positions()[n] + 1e-4 * Eigen::Vector3d::Random();
        sa.velocities()[n] = Eigen::Vector3d::Random();
    }
    cut::transfer_between_levels(grid, a, sa, b, sb);
    std::vector<unsigned char> tied(b.node_count(), 0);
    for (const grid::MixedLevels::Tie& t : b.ties()) tied[t.node] = 1;
    std::size_t shared = 0;
    for (std::uint32_t m = 0; m < b.node_count(); ++m)
        for (std::uint32_t n = 0; n < a.node_count(); ++n)
            if (!tied[m] && a.node_levels()[n] == b.node_levels()[m] && a.grid_node()[n] == b.grid_node()[m]) {
                EXPECT_EQ(sb.positions()[m], sa.positions()[n]) << m;
                EXPECT_EQ(sb.velocities()[m], sa.velocities()[n]) << m;
                ++shared;
            }
    EXPECT_EQ(shared, 100u) << "cell 1's 125 fine nodes but the 25 tied to cell 0 in the new model";
    for (const grid::MixedLevels::Tie& t : b.ties()) {
        Eigen::Vector3d u = Eigen::Vector3d::Zero();
        for (std::size_t c = 0; c < 8; ++c) u += t.weights[c] * (sb.positions()[t.masters[c]] - b.rest_positions()[t.masters[c]]);
        EXPECT_LT((sb.positions()[t.node] - b.rest_positions()[t.node] - u).norm(), 1e-15);
    }
}
