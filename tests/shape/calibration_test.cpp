// The calibration of shape matching's stiffness against the FEM (shape/cluster_hierarchy.hpp,
// k_calibration): a cantilever held at one end sags under gravity as the corotational FEM's does at
// the same E, level and voxels. The calibrated case and two others (another level, another
// section) are measured; docs/shape-matching.md quotes the numbers.

#include "shape/shape_matching.hpp"

#include "fem/block_grid.hpp"

#include <gtest/gtest.h>

#include <cstdio>

using namespace vox;

namespace {

/// Tip sag (m) of a beam of `size_mm` held at x = 0 under gravity, quasi-static, by the FEM or by
/// shape matching at `level`.
double tip_sag(const Eigen::Vector3d& size_mm, int level, bool shape_matching)
{
    const grid::BranchedGrid grid = test::block_grid(size_mm, std::min(6, level + 2));
    const fem::HexModel model(grid, level);
    fem::SolverOptions o;
    o.quasi_static = true;
    o.cg_tolerance = 1e-10;
    o.cg_max_iterations = 5000;
    o.newton_max_iterations = 50;
    fem::ImplicitSolver solver(model, o);
    if (shape_matching) {
        shape::Settings s;
        s.adaptive = false;
        s.max_iterations = 200000;
        s.termination_rate = 1e-12;
        auto sm = std::make_unique<shape::ShapeMatching>(grid, model, s);
        const shape::ShapeMatching* integrator = sm.get();
        solver.set_integrator(std::move(sm));
        for (std::uint32_t n : test::nodes_at(model, 0, -0.5e-3)) solver.fix(n, 7);
        solver.set_gravity(Eigen::Vector3d(0, 0, -9.81));
        solver.step();
        EXPECT_TRUE(integrator->last_step().converged) << integrator->last_step().total_iterations << " iterations";
        double sag = 0.0;
        for (std::uint32_t n = 0; n < model.node_count(); ++n)
            sag = std::max(sag, model.rest_positions()[n].z() - solver.positions()[n].z());
        return sag;
    }
    for (std::uint32_t n : test::nodes_at(model, 0, -0.5e-3)) solver.fix(n, 7);
    solver.set_gravity(Eigen::Vector3d(0, 0, -9.81));
    solver.step();
    double sag = 0.0;
    for (std::uint32_t n = 0; n < model.node_count(); ++n)
        sag = std::max(sag, model.rest_positions()[n].z() - solver.positions()[n].z());
    return sag;
}

double ratio(const Eigen::Vector3d& size_mm, int level)
{
    const double fem = tip_sag(size_mm, level, false), sm = tip_sag(size_mm, level, true);
    std::printf("beam %g x %g x %g mm, level %d: FEM sag %.6g mm, shape matching %.6g mm, ratio %.4f\n", size_mm.x(), size_mm.y(),
                size_mm.z(), level, fem * 1e3, sm * 1e3, sm / fem);
    return sm / fem;
}

} // namespace

TEST(ShapeMatchingCalibration, ACantileverSagsAsTheFemDoes)
{
    // The calibrated case (measured 1.0044): within 1 %.
    EXPECT_NEAR(ratio({32, 4, 4}, 1), 1.0, 0.01);
}

TEST(ShapeMatchingCalibration, OtherBeamsSagWithinTheStatedError)
{
    // Cases the constant was not fitted to: another level and another section (docs/shape-matching.md).
    EXPECT_NEAR(ratio({64, 8, 8}, 2), 1.0, 0.03);
    EXPECT_NEAR(ratio({32, 8, 4}, 1), 1.0, 0.03);
}
