// The Is-XFEM solver: a free bar keeps its momentum; a bar held at one end and cut through falls in
// two, the far piece as a body in free fall (implicit Euler's own free fall, to 10 %), the held
// piece staying, for k = 0 and k = 0.1; uncut, the same bar only sags; a cut made at rest moves
// nothing; only cuts that separate a tetrahedron whole are kept.

#include "isxfem/xfem_solver.hpp"

#include <gtest/gtest.h>

using namespace vox;
using namespace vox::isxfem;

namespace {

constexpr double k_h = 0.01; // 8 x 2 x 2 cubes of 10 mm

XfemModel bar_model(double k)
{
    TetMesh bar = cube_lattice({8, 2, 2}, k_h);
    const std::size_t tets = bar.tets.size();
    return XfemModel(std::move(bar), {TetMaterial{grid::lame_from_young_poisson(1e6, 0.3), 1000.0}}, std::vector<std::uint32_t>(tets, 0), k);
}

/// Mean z of the nodes whose rest x lies in [from, to].
double mean_z(const XfemModel& model, const XfemSolver& solver, double from, double to)
{
    double sum = 0.0;
    int count = 0;
    for (std::size_t n = 0; n < model.node_count(); ++n)
        if (model.mesh().nodes[n].x() >= from && model.mesh().nodes[n].x() <= to) {
            sum += solver.state()[n].z();
            ++count;
        }
    return sum / count;
}

} // namespace

TEST(XfemSolver, AFreeCutBarKeepsItsMomentum)
{
    XfemModel model = bar_model(0.1);
    model.cut(PlaneCut{Eigen::Vector3d(1, 0.2, 0).normalized(), 0.043});
    XfemOptions o;
    o.cg_tolerance = 1e-12;
    XfemSolver solver(model, o);
    for (std::size_t n = 0; n < model.node_count(); ++n)
        solver.velocities()[n] = Eigen::Vector3d(0.1, 0, 0) + Eigen::Vector3d(0, 0, 2.0).cross(model.mesh().nodes[n]);
    const Eigen::Vector3d p0 = solver.momentum();
    for (int k = 0; k < 20; ++k) ASSERT_TRUE(solver.step().converged);
    EXPECT_LT((solver.momentum() - p0).norm(), 1e-8 * p0.norm());
}

TEST(XfemSolver, ABarCutThroughFallsInTwo)
{
    for (double k : {0.0, 0.1}) {
        SCOPED_TRACE("k = " + std::to_string(k));
        for (bool cut : {false, true}) {
            XfemModel model = bar_model(k);
            if (cut) {
                const CutReport r = model.cut(PlaneCut{Eigen::Vector3d::UnitX(), 0.0437});
                EXPECT_EQ(r.cut_tets, 6u * 4u); // the 2 x 2 cubes of the slab, six tetrahedra each
                EXPECT_EQ(r.new_blocks, 18u);   // both node planes of the slab
            }
            XfemOptions o;
            o.cg_tolerance = 1e-8;
            XfemSolver solver(model, o);
            solver.set_gravity({0, 0, -9.81});
            for (std::size_t n = 0; n < model.node_count(); ++n)
                if (model.mesh().nodes[n].x() < 1e-9) solver.fix(static_cast<std::uint32_t>(n), 7);
            const double far0 = mean_z(model, solver, 0.055, 1.0), near0 = mean_z(model, solver, 0.0, 0.025);
            const int steps = 10;
            for (int s = 0; s < steps; ++s) ASSERT_TRUE(solver.step().converged) << "step " << s;
            const double far_drop = far0 - mean_z(model, solver, 0.055, 1.0), near_drop = near0 - mean_z(model, solver, 0.0, 0.025);
            // Implicit Euler falls 1/2 g dt^2 n (n + 1).
            const double free_fall = 0.5 * 9.81 * 1e-4 * steps * (steps + 1);
            if (cut) {
                EXPECT_NEAR(far_drop, free_fall, 0.1 * free_fall);
                EXPECT_LT(near_drop, 0.005);
            } else {
                EXPECT_LT(far_drop, 0.005);
            }
        }
    }
}

TEST(XfemSolver, ACutAtRestMovesNothingAndPartialCutsAreLeft)
{
    XfemModel model = bar_model(0.1);
    // Only the part of the plane with y < 12 mm: it crosses the tetrahedra of the first row of
    // cubes whole, those straddling y = 12 mm partly, the rest not at all.
    const CutReport r = model.cut(PlaneCut{Eigen::Vector3d::UnitX(), 0.0437}, [](const Eigen::Vector3d& p) { return p.y() < 0.012; });
    EXPECT_GT(r.cut_tets, 0u);
    EXPECT_GT(r.partial_tets, 0u);
    EXPECT_EQ(r.cut_tets + r.partial_tets, 24u);
    XfemSolver solver(model, XfemOptions{});
    for (std::size_t t = 0; t < model.elements().size(); ++t)
        for (int side : {0, 1}) {
            const std::array<double, 4> n{0.1, 0.2, 0.3, 0.4};
            Eigen::Vector3d rest = Eigen::Vector3d::Zero();
            for (std::size_t c = 0; c < 4; ++c) rest += n[c] * model.mesh().nodes[model.elements()[t].node[c]];
            EXPECT_LT((solver.position(t, n, side) - rest).norm(), 1e-15);
        }
    const XfemStepStats s = solver.step(); // no gravity, at rest: nothing moves
    EXPECT_EQ(s.cg_iterations, 0);
    EXPECT_EQ(solver.kinetic_energy(), 0.0);
    // A second cut through the same tetrahedra leaves them as they are, and says so.
    const CutReport again = model.cut(PlaneCut{Eigen::Vector3d::UnitX(), 0.0441});
    EXPECT_EQ(again.already_cut, r.cut_tets);
}

TEST(XfemSolver, ACutContinuedLaterIsOneCrack)
{
    XfemModel once = bar_model(0.1), twice = bar_model(0.1);
    const PlaneCut plane{Eigen::Vector3d::UnitX(), 0.0437};
    const CutReport whole = once.cut(plane);
    const CutReport first = twice.cut(plane, [](const Eigen::Vector3d& p) { return p.y() < 0.012; });
    const CutReport rest = twice.cut(plane, {}, first.cut);
    EXPECT_EQ(rest.cut, first.cut);
    EXPECT_EQ(rest.already_cut, 0u); // its own tetrahedra are not "another cut's"
    EXPECT_EQ(twice.cut_count(), 1);
    EXPECT_EQ(first.cut_tets + rest.cut_tets, whole.cut_tets);
    EXPECT_EQ(twice.block_count(), once.block_count()); // shared nodes kept their blocks
    EXPECT_THROW(twice.cut(plane, {}, 5), std::invalid_argument);
}
