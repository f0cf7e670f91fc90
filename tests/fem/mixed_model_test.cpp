// A model of two levels (fem/hex_model.hpp from grid/mixed_levels.hpp) solved with its border
// nodes tied to the coarse side (fem/implicit_solver.hpp): the same mass as one level; a press
// on a soft block, fine (level 1) around the indenter and coarse (level 3) elsewhere, stores the
// energy, and so gives the force, of the uniform level-1 block to within 5 % (measured +3.6 %, with
// 479 nodes against 2,601; the uniform level-3 block is 21 % off); the tied nodes end on the coarse
// elements' field.

#include "fem/hex_model.hpp"
#include "fem/implicit_solver.hpp"
#include "fem/rest_cholesky.hpp"
#include "grid/mixed_levels.hpp"

#include "block_grid.hpp"

#include <gtest/gtest.h>

#include <cstdio>
#include <limits>
#include <memory>
#include <numeric>

namespace vox::fem {
namespace {

/// A 32 x 32 x 16 mm block on a table (bottom held), a 5 x 5 mm square of its top bonded to an
/// indenter pushed 0.5 mm down: the elastic energy at static equilibrium, J.
double press_energy(const HexModel& model, int* iterations = nullptr, bool factor = false)
{
    SolverOptions o;
    o.quasi_static = true;
    o.cg_tolerance = 1e-9;
    o.cg_max_iterations = 5000;
    o.newton_max_iterations = 20;
    o.matrix_free = !factor;
    ImplicitSolver solver(model, o);
    if (factor) solver.set_preconditioner(std::make_unique<RestCholesky>(model.frame(), 25, std::numeric_limits<double>::infinity()));
    solver.set_gravity(Eigen::Vector3d::Zero());
    const double depth = 0.5e-3;
    for (std::uint32_t n = 0; n < model.node_count(); ++n) {
        const Eigen::Vector3d& p = model.rest_positions()[n];
        if (std::abs(p.z() + 0.5e-3) < 1e-9) solver.fix(n, 7u);
        if (std::abs(p.z() - 15.5e-3) < 1e-9 && std::abs(p.x() - 15.5e-3) <= 2.5e-3 + 1e-9 && std::abs(p.y() - 15.5e-3) <= 2.5e-3 + 1e-9) {
            solver.fix(n, 7u);
            solver.positions()[n].z() -= depth;
        }
    }
    const StepStats s = solver.step();
    EXPECT_TRUE(s.converged) << "residual " << s.residual;
    if (iterations) *iterations = s.cg_iterations;
    // The tied nodes lie on their coarse elements' field.
    for (const grid::MixedLevels::Tie& t : model.ties()) {
        Eigen::Vector3d on = Eigen::Vector3d::Zero();
        for (std::size_t c = 0; c < 8; ++c) on += t.weights[c] * solver.positions()[t.masters[c]];
        EXPECT_LT((solver.positions()[t.node] - on).norm(), 1e-12);
    }
    return s.elastic_energy_j;
}

TEST(MixedModel, PressingFineAroundTheIndenterAndCoarseElsewhereGivesTheFineBlocksForce)
{
    const grid::BranchedGrid grid = test::block_grid({32, 32, 16}, 3);
    // The coarse cells within 10 mm of the indenter's centre (15.5, 15.5, 15.5) mm: the top four.
    const grid::MixedLevels mixed(grid, 1, 3, [&](std::uint32_t e) {
        const Eigen::Vector3d middle = (grid.level(3).elements[e].cell.cast<double>() + Eigen::Vector3d::Constant(0.5)) * 8.0 -
                                       Eigen::Vector3d::Constant(0.5);
        return (middle - Eigen::Vector3d::Constant(15.5)).norm() < 10.0;
    });
    ASSERT_EQ(mixed.coarse_elements(), 28u);
    ASSERT_EQ(mixed.fine_elements(), 4u * 64u);
    const HexModel fine(grid, 1), coarse(grid, 3), both(grid, mixed);
    const double mass = fine.total_mass() - std::accumulate(fine.added_mass().begin(), fine.added_mass().end(), 0.0);
    EXPECT_NEAR(both.total_mass() - std::accumulate(both.added_mass().begin(), both.added_mass().end(), 0.0), mass, 1e-12 * mass);

    int iterations_fine = 0, iterations_both = 0;
    const double e_fine = press_energy(fine, &iterations_fine), e_coarse = press_energy(coarse), e_both = press_energy(both, &iterations_both);
    // Same displacement: the force is 2 E / depth, so the energies' ratio is the forces'.
    std::printf("press energy: level 1 %.6g J, level 3 %.6g J, mixed 1/3 %.6g J (%+.2f %%, level 3 %+.2f %%); CG iterations %d / %d; "
                "nodes %zu / %zu\n",
                e_fine, e_coarse, e_both, 100.0 * (e_both / e_fine - 1.0), 100.0 * (e_coarse / e_fine - 1.0), iterations_fine,
                iterations_both, fine.node_count(), both.node_count());
    EXPECT_NEAR(e_both / e_fine, 1.0, 0.05);
    // The warped Cholesky factor of the whole matrix, restricted to the free nodes, preconditions
    // the same solve on the free space to the same answer (though no faster than Jacobi: 193
    // against 182 iterations; the factor to take is that of T^T A T).
    EXPECT_NEAR(press_energy(both, nullptr, true) / e_both, 1.0, 1e-6);
    EXPECT_GT(std::abs(e_coarse / e_fine - 1.0), 0.1) << "the coarse block should be visibly off: the test would show nothing";
}

} // namespace
} // namespace vox::fem
