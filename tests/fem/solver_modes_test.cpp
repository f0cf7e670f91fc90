// The solver's alternatives agree with each other and with mechanics: matrix-free and assembled
// products, the warped Cholesky preconditioner and plain Jacobi, lumped and consistent mass;
// inverted elements recover; plasticity keeps a sculpted shape; wetting softens by its law.

#include "core/error.hpp"
#include "fem/implicit_solver.hpp"
#include "fem/rest_cholesky.hpp"

#include "fem/block_grid.hpp"

#include <Eigen/Geometry>
#include <gtest/gtest.h>

using namespace vox;
using namespace vox::fem;

namespace {

using test::block_grid;
using test::k_e;
using test::k_nu;
using test::nodes_at;

/// Holds the nodes at x = -0.5 mm (the block's first face).
void clamp(const HexModel& model, ImplicitSolver& solver)
{
    for (std::uint32_t n : nodes_at(model, 0, -0.0005)) solver.fix(n, 7);
}

/// Pushes the nodes of the far face (x = length - 0.5 mm) with `force` (N) in total.
void push_end(const HexModel& model, ImplicitSolver& solver, double length_mm, const Eigen::Vector3d& force)
{
    const std::vector<std::uint32_t> end = nodes_at(model, 0, (length_mm - 0.5) * 1e-3);
    for (std::uint32_t n : end) solver.external_forces()[n] = force / static_cast<double>(end.size());
}

double max_difference(const ImplicitSolver& a, const ImplicitSolver& b)
{
    double d = 0.0;
    for (std::size_t n = 0; n < a.positions().size(); ++n) d = std::max(d, (a.positions()[n] - b.positions()[n]).norm());
    return d;
}

} // namespace

TEST(SolverModes, MatrixFreeProductMatchesTheAssembledMatrix)
{
    // A cantilever swinging under gravity, large enough to rotate its elements.
    const auto grid = block_grid({16, 4, 4}, 2);
    const HexModel model(grid, 1);
    for (bool lumped : {true, false}) {
        SCOPED_TRACE(lumped ? "lumped" : "consistent");
        SolverOptions o;
        o.cg_tolerance = 1e-12;
        o.cg_max_iterations = 2000;
        o.lumped_mass = lumped;
        ImplicitSolver assembled(model, o);
        o.matrix_free = true;
        ImplicitSolver matrix_free(model, o);
        for (ImplicitSolver* s : {&assembled, &matrix_free}) {
            s->set_gravity({0, 0, -9.81});
            clamp(model, *s);
        }
        StepStats a;
        for (int k = 0; k < 10; ++k) {
            a = assembled.step();
            const StepStats b = matrix_free.step();
            EXPECT_TRUE(a.converged && b.converged);
        }
        EXPECT_GT(a.max_displacement_m, 1e-5);
        EXPECT_LT(max_difference(assembled, matrix_free), 1e-9 * a.max_displacement_m);
    }
}

TEST(SolverModes, MatrixFreeRefusesAPreconditionerThatNeedsTheMatrix)
{
    const auto grid = block_grid({4, 4, 4}, 2);
    const HexModel model(grid, 1);
    SolverOptions o;
    o.matrix_free = true;
    ImplicitSolver solver(model, o);
    EXPECT_THROW(solver.set_preconditioner(std::make_unique<RestCholesky>(model.frame())), InputError);
}

TEST(SolverModes, WarpedCholeskyConvergesToTheSameStateInFewIterations)
{
    const auto grid = block_grid({24, 4, 4}, 2);
    const HexModel model(grid, 1);
    SolverOptions o;
    o.cg_tolerance = 1e-10;
    o.cg_max_iterations = 5000;
    ImplicitSolver jacobi(model, o), warped(model, o);
    warped.set_preconditioner(std::make_unique<RestCholesky>(model.frame()));
    int jacobi_iterations = 0, warped_iterations = 0;
    for (ImplicitSolver* s : {&jacobi, &warped}) {
        s->set_gravity({0, 0, -9.81});
        clamp(model, *s);
    }
    StepStats s;
    for (int k = 0; k < 20; ++k) {
        s = jacobi.step();
        jacobi_iterations += s.cg_iterations;
        warped_iterations += warped.step().cg_iterations;
    }
    EXPECT_LT(max_difference(jacobi, warped), 1e-6 * s.max_displacement_m);
    EXPECT_LT(4 * warped_iterations, jacobi_iterations);
}

TEST(SolverModes, WarpedCholeskyWithoutSupportFallsBackToJacobi)
{
    // Quasi-static with nothing held: K is singular, the factor fails, Jacobi takes over and says so.
    const auto grid = block_grid({4, 4, 4}, 2);
    const HexModel model(grid, 1);
    SolverOptions o;
    o.quasi_static = true;
    o.newton_max_iterations = 1;
    ImplicitSolver solver(model, o);
    solver.set_preconditioner(std::make_unique<RestCholesky>(model.frame()));
    solver.external_forces()[0] = {0, 0, 1e-3};
    const StepStats s = solver.step();
    EXPECT_TRUE(std::isfinite(s.elastic_energy_j));
    EXPECT_NE(solver.fallback_note().find("Jacobi"), std::string::npos);
}

TEST(SolverModes, InvertedElementsTurnBackOut)
{
    // Mirror a free 4 mm cube through its mid-plane: every element inside out. The proper
    // rotation (never a reflection) makes the elastic forces push it back to a right-handed state.
    const auto grid = block_grid({4, 4, 4}, 2);
    const HexModel model(grid, 1);
    SolverOptions o;
    o.rayleigh_mass_per_s = 5.0;
    o.rayleigh_stiffness_s = 0.01;
    o.dt_s = 1e-3;
    ImplicitSolver solver(model, o);
    for (auto& x : solver.positions()) x.z() = 0.0015 - x.z();
    auto signed_volume = [&] {
        const HexElement& el = model.elements()[0];
        const auto& x = solver.positions();
        return (x[el.dof_node[1]] - x[el.dof_node[0]]).cross(x[el.dof_node[2]] - x[el.dof_node[0]]).dot(x[el.dof_node[4]] - x[el.dof_node[0]]);
    };
    ASSERT_LT(signed_volume(), 0.0);
    StepStats s;
    for (int k = 0; k < 400; ++k) {
        s = solver.step();
        ASSERT_TRUE(std::isfinite(s.elastic_energy_j) && std::isfinite(s.kinetic_energy_j)) << "step " << k;
    }
    EXPECT_GT(signed_volume(), 0.0);
    EXPECT_LT(s.elastic_energy_j, 1e-9);
}

TEST(SolverModes, PlasticityKeepsASculptedShapeAndBoundsTheStrain)
{
    // Push the free end of a clamped bar sideways, then let go: an elastic bar springs back, a
    // plastic one keeps part of the bend; the plastic strain never exceeds max_strain.
    const auto grid = block_grid({16, 4, 4}, 2);
    const HexModel model(grid, 1);
    double kept[2] = {0.0, 0.0};
    for (int plastic = 0; plastic < 2; ++plastic) {
        SolverOptions o;
        o.quasi_static = true;
        o.cg_tolerance = 1e-9;
        o.cg_max_iterations = 2000;
        ImplicitSolver solver(model, o);
        solver.set_preconditioner(std::make_unique<RestCholesky>(model.frame()));
        MaterialBehaviour b;
        if (plastic) {
            b.yield_strain = 0.002;
            b.creep_per_s = 50.0;
            b.max_strain = 0.004;
        }
        solver.set_materials({b});
        EXPECT_EQ(solver.has_plasticity(), plastic == 1);
        clamp(model, solver);
        push_end(model, solver, 16, {0, 1e-3, 0}); // about 1.5 % strain at the root, 0.6 mm at the tip
        double loaded = 0.0;
        for (int k = 0; k < 30; ++k) loaded = solver.step().max_displacement_m;
        push_end(model, solver, 16, {0, 0, 0});
        StepStats s;
        for (int k = 0; k < 5; ++k) s = solver.step();
        kept[plastic] = s.max_displacement_m / loaded;
        for (std::uint32_t e = 0; e < model.elements().size(); ++e) EXPECT_LE(solver.plastic_strain(e).norm(), 0.004 * (1 + 1e-12));
    }
    EXPECT_LT(kept[0], 1e-6);
    EXPECT_GT(kept[1], 0.2);
}

TEST(SolverModes, WettingSoftensByItsLaw)
{
    // Uniaxial tension of a bar held on its first face by slide constraints: displacement
    // F L / (E' A) with E' = E (1 - (1 - ratio) w).
    const auto grid = block_grid({12, 4, 4}, 1);
    const HexModel model(grid, 1);
    const double force = 0.2, length = 12e-3, area = 16e-6;
    for (double water : {0.0, 0.5, 1.0}) {
        SCOPED_TRACE(testing::Message() << "water " << water);
        SolverOptions o;
        o.quasi_static = true;
        o.cg_tolerance = 1e-11;
        o.cg_max_iterations = 4000;
        ImplicitSolver solver(model, o);
        MaterialBehaviour b;
        b.wet_stiffness_ratio = 0.2;
        solver.set_materials({b});
        for (std::uint32_t e = 0; e < model.elements().size(); ++e) solver.set_water(e, water);
        EXPECT_DOUBLE_EQ(solver.water(0), water);
        for (int axis = 0; axis < 3; ++axis)
            for (std::uint32_t n : nodes_at(model, axis, -0.0005)) solver.fix(n, 1u << axis);
        // Consistent nodal loads of a uniform traction on the end face (2 x 2 mm faces).
        for (std::uint32_t n = 0; n < model.node_count(); ++n) {
            const Eigen::Vector3d p = model.rest_positions()[n];
            if (std::abs(p.x() - 0.0115) > 1e-9) continue;
            const bool ey = std::abs(p.y() + 0.0005) < 1e-9 || std::abs(p.y() - 0.0035) < 1e-9;
            const bool ez = std::abs(p.z() + 0.0005) < 1e-9 || std::abs(p.z() - 0.0035) < 1e-9;
            solver.external_forces()[n] = {force * (ey ? 1.0 : 2.0) * (ez ? 1.0 : 2.0) / 16.0, 0, 0};
        }
        const StepStats s = solver.step();
        ASSERT_TRUE(s.converged);
        const double expected = force * length / (k_e * (1.0 - 0.8 * water) * area);
        for (std::uint32_t n : nodes_at(model, 0, 0.0115))
            EXPECT_NEAR(solver.positions()[n].x() - model.rest_positions()[n].x(), expected, 1e-6 * expected);
    }
}

TEST(SolverModes, WarpedCholeskyFollowsARigidRotationExactly)
{
    // Factored at rest, then the whole (free) bar turned rigidly: the rotated system is the rest
    // system seen in the turned frame, so the warped factor solves it in one iteration or two.
    const auto grid = block_grid({16, 4, 4}, 2);
    const HexModel model(grid, 1);
    SolverOptions o;
    o.cg_tolerance = 1e-10;
    o.cg_max_iterations = 500;
    ImplicitSolver solver(model, o);
    solver.set_preconditioner(std::make_unique<RestCholesky>(model.frame()));
    solver.set_gravity({0, 0, -9.81});
    ASSERT_LE(solver.step().cg_iterations, 2); // at rest: the factor is exact
    const Eigen::Matrix3d r = Eigen::AngleAxisd(1.0, Eigen::Vector3d(1, 2, 3).normalized()).toRotationMatrix();
    for (std::size_t n = 0; n < model.node_count(); ++n) {
        solver.positions()[n] = r * model.rest_positions()[n];
        solver.velocities()[n].setZero();
    }
    EXPECT_LE(solver.step().cg_iterations, 2);
}
