#include "fem/implicit_solver.hpp"
#include "fem/multigrid.hpp"

#include "fem/block_grid.hpp"

#include <Eigen/Geometry>
#include <gtest/gtest.h>

#include <random>

using namespace vox;
using namespace vox::fem;

namespace {

using test::block_grid;
using test::k_e;
using test::k_nu;
using test::nodes_at;

/// The bar of the tests below (12 x 4 x 4 elements of h, its near corner at -h/2 on every axis):
/// its three symmetry planes held by slide constraints.
void hold_symmetry_planes(const HexModel& model, ImplicitSolver& solver, double h)
{
    for (int axis = 0; axis < 3; ++axis)
        for (std::uint32_t n : nodes_at(model, axis, -0.5 * h)) solver.fix(n, 1u << axis);
}

/// The consistent loads of a uniform traction adding up to `force` N along x over the bar's far
/// end face (side x side, at x = length - h/2): each element face gives a quarter to its corners.
std::vector<Eigen::Vector3d> end_traction(const HexModel& model, int level, double force, double h, double length, double side)
{
    const double y0 = -0.5 * h, z0 = -0.5 * h, cell = (1 << level) * h;
    std::vector<Eigen::Vector3d> load(model.node_count(), Eigen::Vector3d::Zero());
    for (std::uint32_t n : nodes_at(model, 0, -0.5 * h + length)) {
        const Eigen::Vector3d p = model.rest_positions()[n];
        const bool ey = std::abs(p.y() - y0) < 1e-9 || std::abs(p.y() - (y0 + side)) < 1e-9;
        const bool ez = std::abs(p.z() - z0) < 1e-9 || std::abs(p.z() - (z0 + side)) < 1e-9;
        load[n] = Eigen::Vector3d(force * (ey ? 1.0 : 2.0) * (ez ? 1.0 : 2.0) / 4.0 * cell * cell / (side * side), 0, 0);
    }
    return load;
}

} // namespace

TEST(ImplicitSolver, RigidMotionsStoreNoEnergy)
{
    const auto grid = block_grid({8, 4, 4}, 2);
    const HexModel model(grid, 1);
    SolverOptions o;
    o.quasi_static = true;
    ImplicitSolver solver(model, o);
    const Eigen::Matrix3d r = Eigen::AngleAxisd(0.7, Eigen::Vector3d(1, 2, 3).normalized()).toRotationMatrix();
    for (auto& x : solver.positions()) x = r * x + Eigen::Vector3d(0.01, -0.02, 0.03);
    // No constraint, no load: the first Newton residual is the internal force, which must vanish.
    for (std::uint32_t n : nodes_at(model, 0, -0.0005)) solver.fix(n, 7);
    const StepStats s = solver.step();
    // A 1 % strain of this block would store about 6e-7 J.
    EXPECT_LT(s.elastic_energy_j, 1e-24);
    EXPECT_EQ(s.newton_iterations, 0);
}

TEST(ImplicitSolver, UniaxialCompressionMatchesFLOverEAAndPatchTest)
{
    // A 12 x 4 x 4 mm bar, symmetry planes held by slide constraints, a force F on its far end: a
    // 1.25 % strain, where the linear model holds (fem/volume_correction.hpp leaves it alone).
    const double h = 1e-3, length = 12e-3, side = 4e-3, force = -0.02;
    const auto grid = block_grid({12, 4, 4}, 1);
    for (int level : {0, 1}) {
    SCOPED_TRACE(testing::Message() << "level " << level);
    const HexModel model(grid, level);
    SolverOptions o;
    o.quasi_static = true;
    o.cg_tolerance = 1e-10;
    o.cg_max_iterations = 2000;
    ImplicitSolver solver(model, o);
    const double x0 = -0.5 * h, y0 = -0.5 * h, z0 = -0.5 * h;
    hold_symmetry_planes(model, solver, h);
    solver.external_forces() = end_traction(model, level, force, h, length, side);
    const StepStats s = solver.step();
    ASSERT_TRUE(s.converged);
    // Uniform strain exactly: u_x = eps x, u_y = -nu eps y, u_z = -nu eps z, eps = F / (E A).
    const double eps = force / (k_e * side * side);
    for (std::uint32_t n = 0; n < model.node_count(); ++n) {
        const Eigen::Vector3d p0 = model.rest_positions()[n] - Eigen::Vector3d(x0, y0, z0);
        const Eigen::Vector3d expect(eps * p0.x(), -k_nu * eps * p0.y(), -k_nu * eps * p0.z());
        EXPECT_LT((solver.positions()[n] - model.rest_positions()[n] - expect).norm(), 1e-6 * std::abs(eps) * length);
    }
    // The end moves by F L / (E A).
    const std::uint32_t tip = nodes_at(model, 0, x0 + length).front();
    EXPECT_NEAR(solver.positions()[tip].x() - model.rest_positions()[tip].x(), force * length / (k_e * side * side),
                1e-6 * std::abs(force * length / (k_e * side * side)));
    }
}

TEST(ImplicitSolver, MomentumIsConservedWithoutLoadsAndDamping)
{
    const auto grid = block_grid({6, 4, 4}, 2);
    const HexModel model(grid, 1);
    SolverOptions o;
    o.cg_tolerance = 1e-12;
    o.cg_max_iterations = 1000;
    ImplicitSolver solver(model, o);
    std::mt19937 rng(2);
    std::normal_distribution<double> g(0.0, 0.01);
    for (auto& v : solver.velocities()) v = Eigen::Vector3d(g(rng), g(rng), g(rng));
    const Eigen::Vector3d p0 = solver.momentum();
    for (int k = 0; k < 20; ++k) solver.step();
    EXPECT_LT((solver.momentum() - p0).norm(), 1e-8 * p0.norm());
}

TEST(ImplicitSolver, DampingMakesEnergyDecay)
{
    const auto grid = block_grid({8, 4, 4}, 2);
    const HexModel model(grid, 1);
    SolverOptions o;
    o.rayleigh_mass_per_s = 2.0;
    o.rayleigh_stiffness_s = 0.01;
    o.cg_tolerance = 1e-10;
    ImplicitSolver solver(model, o);
    for (std::uint32_t n : nodes_at(model, 0, -0.0005)) solver.fix(n, 7);
    // Start stretched along x by 1 %, at rest.
    for (std::uint32_t n = 0; n < model.node_count(); ++n) solver.positions()[n].x() *= 1.01;
    double previous = std::numeric_limits<double>::infinity();
    for (int k = 0; k < 30; ++k) {
        const StepStats s = solver.step();
        const double total = s.kinetic_energy_j + s.elastic_energy_j;
        EXPECT_LE(total, previous * (1 + 1e-9)) << "step " << k;
        previous = total;
    }
    EXPECT_LT(previous, 0.5 * solver.step().elastic_energy_j + 1.0); // finite and bounded
}

TEST(Multigrid, PreconditionedSolveMatchesJacobiWithFarFewerIterations)
{
    // A cantilever sagging under gravity, quasi-static: bending makes Jacobi-CG slow.
    const auto grid = block_grid({64, 8, 8}, 4);
    const HexModel model(grid, 1);
    SolverOptions o;
    o.quasi_static = true;
    o.cg_tolerance = 1e-7;
    o.cg_max_iterations = 20000;
    o.newton_max_iterations = 50;
    ImplicitSolver jacobi(model, o), multigrid(model, o);
    multigrid.set_preconditioner(std::make_unique<Multigrid>(grid, model, 4));
    for (ImplicitSolver* s : {&jacobi, &multigrid}) {
        s->set_gravity({0, 0, -9.81});
        for (std::uint32_t n : nodes_at(model, 0, -0.0005)) s->fix(n, 7);
    }
    const StepStats a = jacobi.step(), b = multigrid.step();
    ASSERT_TRUE(a.converged);
    ASSERT_TRUE(b.converged);
    EXPECT_LT(b.cg_iterations * 10, a.cg_iterations);
    for (std::uint32_t n = 0; n < model.node_count(); ++n)
        EXPECT_LT((jacobi.positions()[n] - multigrid.positions()[n]).norm(), 1e-4 * a.max_displacement_m);
}

TEST(ImplicitSolver, ResponseIsTheBarsCondensedComplianceWithoutTheToolsSprings)
{
    // The bar above, held on its symmetry planes, one newton spread over its far end as a uniform
    // traction: the load-weighted end displacement per newton is L / (E A). A stiff tool spring on
    // the end does not change it (the response leaves the tools' springs out: the haptic patch
    // sits in series with them). A dynamic step gives less (the mass resists), approaching the
    // static compliance as the step grows.
    const double h = 1e-3, length = 12e-3, side = 4e-3;
    const auto grid = block_grid({12, 4, 4}, 1);
    const HexModel model(grid, 0);
    auto compliance = [&](bool quasi_static, double dt, bool tool_spring) {
        SolverOptions o;
        o.quasi_static = quasi_static;
        o.dt_s = dt;
        o.cg_tolerance = 1e-10;
        o.cg_max_iterations = 4000;
        ImplicitSolver solver(model, o);
        hold_symmetry_planes(model, solver, h);
        const std::vector<Eigen::Vector3d> load = end_traction(model, 0, 1.0, h, length, side);
        std::vector<NodeContact> springs;
        for (std::uint32_t n : nodes_at(model, 0, -0.5 * h + length)) springs.push_back({n, Eigen::Vector3d::Zero(), 1e6 * Eigen::Matrix3d::Identity()});
        if (tool_spring) solver.set_contact(springs);
        solver.step(); // at rest: nothing moves; the response is taken where the step left the bar
        const std::vector<Eigen::Vector3d> u = solver.response(load);
        EXPECT_EQ(u.size(), model.node_count());
        double c = 0.0;
        for (std::size_t i = 0; i < u.size(); ++i) c += load[i].dot(u[i]);
        return c;
    };
    const double expected = length / (k_e * side * side);
    EXPECT_NEAR(compliance(true, 0.01, false), expected, 1e-6 * expected);
    EXPECT_NEAR(compliance(true, 0.01, true), expected, 1e-6 * expected);
    const double frame = compliance(false, 0.01, false), long_step = compliance(false, 10.0, false);
    EXPECT_LT(frame, expected);
    EXPECT_GT(frame, 0.0);
    EXPECT_NEAR(long_step, expected, 1e-3 * expected);
}
