// The Is-XFEM solver: a free bar keeps its momentum; a bar held at one end and cut through falls in
// two, the far piece as a body in free fall (implicit Euler's own free fall, to 10 %), the held
// piece staying, for k = 0 and k = 0.1; uncut, the same bar only sags; a cut made at rest moves
// nothing; only cuts that separate a tetrahedron whole are kept; two cuts through one slab cut it
// in three (the slice falls too), one alongside an earlier within a hundredth of a tetrahedron is
// left to it; cuts crossing inside a tetrahedron are counted; after a cut the
// warped factor is kept and corrected, and stays a sound preconditioner.

#include "isxfem/xfem_solver.hpp"

#include "core/error.hpp"
#include "fem/rest_cholesky.hpp"
#include "isxfem/plane_cut_system.hpp"

#include <Eigen/Cholesky>
#include <Eigen/Eigenvalues>

#include <gtest/gtest.h>

using namespace vox;
using namespace vox::isxfem;

namespace {

constexpr double k_h = 0.01; // 8 x 2 x 2 cubes of 10 mm

XfemModel bar_model(double k)
{
    TetMesh bar = cube_lattice({8, 2, 2}, k_h);
    const std::size_t tets = bar.tets.size();
    return XfemModel(std::move(bar), {grid::ElasticMaterial{grid::lame_from_young_poisson(1e6, 0.3), 1000.0}}, std::vector<std::uint32_t>(tets, 0), k);
}

/// The bar under gravity, held at its end x = 0.
void hang(const XfemModel& model, XfemSolver& solver)
{
    solver.set_gravity({0, 0, -9.81});
    for (std::size_t n = 0; n < model.node_count(); ++n)
        if (model.mesh().nodes[n].x() < 1e-9) solver.fix(static_cast<std::uint32_t>(n), 7);
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
            hang(model, solver);
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
    // A second cut through the same tetrahedra cuts them again (parallel: nothing crossed); a
    // third leaves them as they are, and says so.
    const CutReport again = model.cut(PlaneCut{Eigen::Vector3d::UnitX(), 0.0441});
    EXPECT_EQ(again.recut_tets, r.cut_tets);
    EXPECT_EQ(again.crossed_tets, 0u);
    const CutReport third = model.cut(PlaneCut{Eigen::Vector3d::UnitX(), 0.0445});
    EXPECT_EQ(third.already_cut, r.cut_tets);
}

TEST(XfemSolver, TwoCutsThroughOneSlabCutItInThree)
{
    // Both planes cross the same slab of tetrahedra, 2.5 mm apart: its tetrahedra hold three
    // regions each, which the two enrichments separate whole. The thin slice between the planes
    // falls free as well as the far piece; the held piece stays.
    XfemModel model = bar_model(0.1);
    const CutReport first = model.cut(PlaneCut{Eigen::Vector3d::UnitX(), 0.0437});
    const CutReport second = model.cut(PlaneCut{Eigen::Vector3d::UnitX(), 0.0462});
    EXPECT_EQ(second.cut_tets, first.cut_tets);
    EXPECT_EQ(second.recut_tets, first.cut_tets);
    EXPECT_EQ(second.crossed_tets, 0u);
    for (const XfemElement& el : model.elements()) {
        if (el.cuts.size() == 2) {
            EXPECT_EQ(el.regions.size(), 3u) << "two parallel planes leave three regions";
        }
    }
    XfemOptions o;
    o.cg_tolerance = 1e-8;
    XfemSolver solver(model, o);
    hang(model, solver);
    // A material point in the slice: x = 45 mm, in a tetrahedron cut twice.
    std::size_t slice_tet = model.elements().size();
    std::array<double, 4> bary{};
    for (std::size_t t = 0; t < model.elements().size() && slice_tet == model.elements().size(); ++t) {
        if (model.elements()[t].cuts.size() != 2) continue;
        const std::array<double, 4> b = barycentric(model.mesh(), t, Eigen::Vector3d(0.045, 0.005, 0.005));
        if (*std::min_element(b.begin(), b.end()) >= 0.0) {
            slice_tet = t;
            bary = b;
        }
    }
    ASSERT_LT(slice_tet, model.elements().size());
    const int slice = static_cast<int>(model.elements()[slice_tet].region_at(bary));
    EXPECT_EQ(slice, 1); // past the first plane, before the second
    const double slice0 = solver.position(slice_tet, bary, slice).z(), far0 = mean_z(model, solver, 0.055, 1.0),
                 near0 = mean_z(model, solver, 0.0, 0.025);
    const int steps = 10;
    for (int s = 0; s < steps; ++s) ASSERT_TRUE(solver.step().converged) << "step " << s;
    const double free_fall = 0.5 * 9.81 * 1e-4 * steps * (steps + 1);
    EXPECT_NEAR(slice0 - solver.position(slice_tet, bary, slice).z(), free_fall, 0.1 * free_fall);
    EXPECT_NEAR(far0 - mean_z(model, solver, 0.055, 1.0), free_fall, 0.1 * free_fall);
    EXPECT_LT(near0 - mean_z(model, solver, 0.0, 0.025), 0.005);
}

TEST(XfemSolver, ASecondCutBesideTheFirstIsLeftToItOnlyForASliver)
{
    // Through x = 45 mm, then again beside it in the same slab of 10 mm tetrahedra. At 0.01 mm (a
    // blade drawn again along its crack) the sliver between the two would hold dofs the solve
    // cannot (a haptic session cutting one plane over and over diverged), so the earlier crack is
    // taken to separate it; at 3.5 mm the second clips corners of some tetrahedra, no sliver
    // between the two, and cuts them all.
    for (const auto& [second_x, left_to_first] : {std::pair{0.04501, true}, std::pair{0.0415, false}}) {
        XfemModel model = bar_model(0.1);
        const CutReport first = model.cut(PlaneCut{Eigen::Vector3d::UnitX(), 0.045});
        const CutReport second = model.cut(PlaneCut{Eigen::Vector3d::UnitX(), second_x});
        EXPECT_EQ(second.beside_earlier, left_to_first ? first.cut_tets : 0u) << second_x;
        EXPECT_EQ(second.cut_tets, left_to_first ? 0u : first.cut_tets) << second_x;
        if (!left_to_first) continue;
        // The bar then falls as after the one cut.
        XfemSolver solver(model, XfemOptions{});
        hang(model, solver);
        const double far0 = mean_z(model, solver, 0.055, 1.0);
        const int steps = 10;
        for (int s = 0; s < steps; ++s) ASSERT_TRUE(solver.step().converged) << "step " << s;
        const double free_fall = 0.5 * 9.81 * 1e-4 * steps * (steps + 1);
        EXPECT_NEAR(far0 - mean_z(model, solver, 0.055, 1.0), free_fall, 0.1 * free_fall);
    }
}

TEST(XfemSolver, ASecondCutThroughFallingTetrahedraIsPatchedIn)
{
    // The bar cut once and falling, then cut again through the same slab while it moves: the new
    // regions start from the rotations of the ones they split, the warped factor is kept and
    // corrected (or taken again when that pays), and the steps go on converging in a few iterations,
    // the far piece in free fall.
    XfemModel model = bar_model(0.1);
    model.cut(PlaneCut{Eigen::Vector3d::UnitX(), 0.0437});
    XfemOptions o;
    o.cg_tolerance = 1e-8;
    XfemSolver solver(model, o);
    auto owned = std::make_unique<fem::RestCholesky>(Eigen::Matrix3d::Identity());
    const fem::RestCholesky* warped = owned.get();
    solver.set_preconditioner(std::move(owned));
    hang(model, solver);
    const double far0 = mean_z(model, solver, 0.055, 1.0);
    for (int s = 0; s < 3; ++s) ASSERT_TRUE(solver.step().converged);
    const CutReport again = model.cut(PlaneCut{Eigen::Vector3d::UnitX(), 0.0462});
    ASSERT_GT(again.recut_tets, 0u);
    solver.model_changed();
    const int steps = 10;
    for (int s = 0; s < steps; ++s) {
        const XfemStepStats st = solver.step();
        ASSERT_TRUE(st.converged) << "step " << s;
        EXPECT_LT(st.cg_iterations, 40) << "step " << s;
    }
    EXPECT_FALSE(warped->failed());
    const double free_fall = 0.5 * 9.81 * 1e-4 * (steps + 3) * (steps + 4);
    EXPECT_NEAR(far0 - mean_z(model, solver, 0.055, 1.0), free_fall, 0.1 * free_fall);
}

TEST(XfemSolver, CutsThatCrossInsideATetrahedronAreCounted)
{
    // Across, then lengthwise through the bar's middle: the slab's tetrahedra the second plane
    // crosses hold four regions, which three linear fields cannot move apart independently.
    XfemModel model = bar_model(0.1);
    model.cut(PlaneCut{Eigen::Vector3d::UnitX(), 0.0437});
    const CutReport lengthwise = model.cut(PlaneCut{Eigen::Vector3d(0.0, 0.1, 1.0).normalized(), 0.0101});
    EXPECT_GT(lengthwise.recut_tets, 0u);
    EXPECT_GT(lengthwise.crossed_tets, 0u);
    std::size_t crossed = 0;
    for (const XfemElement& el : model.elements()) {
        crossed += el.crossed ? 1 : 0;
        if (el.crossed) {
            EXPECT_EQ(el.regions.size(), 4u);
        }
    }
    EXPECT_EQ(crossed, lengthwise.crossed_tets);
    XfemOptions o;
    o.cg_tolerance = 1e-8;
    XfemSolver solver(model, o);
    hang(model, solver);
    for (int s = 0; s < 5; ++s) ASSERT_TRUE(solver.step().converged) << "step " << s;
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

TEST(XfemSolver, ACutKeepsTheWarpedFactorAndSolvesThePatchBesideIt)
{
    // A bar 20 x 4 x 2 cubes, held at one end, factored, then cut through its upper cubes only:
    // the preconditioner keeps its factor and adds an exact solve on the new enriched blocks and
    // their neighbours. The result is symmetric positive definite with P A's eigenvalues in
    // (0, 2] (additive Schwarz with one overlap), and the step converges without a new factor.
    auto slab = [] {
        TetMesh mesh = cube_lattice({20, 4, 2}, k_h);
        const std::size_t tets = mesh.tets.size();
        return XfemModel(std::move(mesh), {grid::ElasticMaterial{grid::lame_from_young_poisson(1e5, 0.3), 1000.0}}, std::vector<std::uint32_t>(tets, 0), 0.1);
    };
    const PlaneCut plane{Eigen::Vector3d::UnitX(), 0.1003};
    auto upper = [](const Eigen::Vector3d& q) { return q.z() > 0.0099; };
    XfemModel model = slab();
    XfemOperator op(model);
    std::vector<Eigen::Vector3d> x = model.mesh().nodes;
    std::vector<unsigned char> fixed(3 * x.size(), 0);
    for (std::size_t n = 0; n < model.node_count(); ++n)
        if (model.mesh().nodes[n].x() < 1e-9) fixed[3 * n] = fixed[3 * n + 1] = fixed[3 * n + 2] = 1;
    op.update(x, fixed, 1.0, 1e-4);
    fem::RestCholesky p(Eigen::Matrix3d::Identity());
    p.set_exact_cuts(false); // as the Is-XFEM simulation takes it
    std::vector<Eigen::Quaterniond> rotation(x.size(), Eigen::Quaterniond::Identity());
    p.update(&op.matrix(), fixed, rotation);
    const CutReport r = model.cut(plane, upper);
    ASSERT_GT(r.new_blocks, 0u);
    op.model_changed();
    x.resize(model.block_count(), Eigen::Vector3d::Zero());
    fixed.resize(3 * x.size(), 0);
    rotation.resize(x.size(), Eigen::Quaterniond::Identity());
    op.update(x, fixed, 1.0, 1e-4);
    p.blocks_changed({});
    p.update(&op.matrix(), fixed, rotation);
    EXPECT_EQ(p.factorizations(), 1);
    EXPECT_GT(p.patch_dofs(), 3 * r.new_blocks);

    const Eigen::MatrixXd a(op.matrix());
    const Eigen::Index n = a.rows();
    Eigen::MatrixXd pm(n, n);
    for (Eigen::Index i = 0; i < n; ++i) {
        Eigen::VectorXd e = Eigen::VectorXd::Zero(n), z;
        e[i] = 1.0;
        p.apply(e, z);
        pm.col(i) = z;
    }
    EXPECT_LT((pm - pm.transpose()).norm(), 1e-6 * pm.norm()); // the factor is applied in single precision
    std::vector<Eigen::Index> free;
    for (Eigen::Index i = 0; i < n; ++i)
        if (!fixed[static_cast<std::size_t>(i)]) free.push_back(i);
    const auto m = static_cast<Eigen::Index>(free.size());
    Eigen::MatrixXd pf(m, m), af(m, m);
    for (Eigen::Index i = 0; i < m; ++i)
        for (Eigen::Index j = 0; j < m; ++j) {
            pf(i, j) = 0.5 * (pm(free[i], free[j]) + pm(free[j], free[i]));
            af(i, j) = a(free[i], free[j]);
        }
    // The eigenvalues of P A are those of L^T P L, A = L L^T: symmetric, so real.
    const Eigen::MatrixXd l = af.llt().matrixL();
    const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> pa(l.transpose() * pf * l);
    EXPECT_GT(pa.eigenvalues().minCoeff(), 0.05);
    EXPECT_LT(pa.eigenvalues().maxCoeff(), 2.0 + 1e-4);

    // The solver does the same: after the cut it converges on the kept factor.
    XfemModel again = slab();
    XfemSolver solver(again, XfemOptions{});
    auto owned = std::make_unique<fem::RestCholesky>(Eigen::Matrix3d::Identity());
    const fem::RestCholesky* warped = owned.get();
    solver.set_preconditioner(std::move(owned));
    solver.set_gravity({0, 0, -9.81});
    for (std::size_t node = 0; node < again.node_count(); ++node)
        if (again.mesh().nodes[node].x() < 1e-9) solver.fix(static_cast<std::uint32_t>(node), 7);
    solver.step();
    again.cut(plane, upper);
    solver.model_changed();
    const XfemStepStats s = solver.step();
    EXPECT_TRUE(s.converged);
    EXPECT_LE(s.cg_iterations, 25);
    EXPECT_EQ(warped->factorizations(), 1);
}

TEST(XfemSolver, VolumeRatiosMatchThePlaneCutSystemAndTheRegularisationTakesTheSmallOnes)
{
    // The model's volume ratio of each enriched block (summed over its cut tetrahedra) against the plane-cut
    // assembly's (computed from the whole mesh at once), on a cut 1e-3 h from a node plane.
    const PlaneCut plane{Eigen::Vector3d::UnitX(), 4.001 * k_h};
    XfemModel model = bar_model(0.0);
    model.cut(plane);
    const PlaneCutSystem reference = assemble_plane_cut(cube_lattice({8, 2, 2}, k_h), plane, 0.0, grid::lame_from_young_poisson(1e6, 0.3), 1000.0);
    std::size_t small = 0;
    for (auto b = static_cast<std::uint32_t>(model.node_count()); b < model.block_count(); ++b) {
        const std::uint32_t node = model.enriched_node(b);
        ASSERT_GE(reference.enriched[node], 0);
        const double expected = reference.volume_ratio[3 * (model.node_count() + static_cast<std::size_t>(reference.enriched[node]))];
        EXPECT_NEAR(model.volume_ratio(b), expected, 1e-12 * std::max(1.0, expected));
        small += model.volume_ratio(b) < 1e-4;
    }
    ASSERT_GT(small, 0u);

    XfemOptions off, on;
    on.regularisation_lambda = 1e-3;
    XfemSolver plain(model, off), regularised(model, on);
    EXPECT_EQ(plain.regularised_blocks(), 0u);
    EXPECT_EQ(regularised.regularised_blocks(), small);
    for (XfemSolver* s : {&plain, &regularised}) {
        s->set_gravity({0, 0, -9.81});
        for (std::size_t n = 0; n < model.node_count(); ++n)
            if (model.mesh().nodes[n].x() < 1e-9) s->fix(static_cast<std::uint32_t>(n), 7);
    }
    XfemStepStats p{}, r{};
    for (int i = 0; i < 5; ++i) {
        p = plain.step();
        r = regularised.step();
    }
    EXPECT_TRUE(p.converged);
    EXPECT_TRUE(r.converged);
    // A + lambda I as added inertia resists the small-ratio jumps: they move less than unregularised.
    double free_jump = 0.0, held_jump = 0.0;
    for (auto b = static_cast<std::uint32_t>(model.node_count()); b < model.block_count(); ++b)
        if (model.volume_ratio(b) < 1e-4) {
            free_jump = std::max(free_jump, plain.velocities()[b].norm());
            held_jump = std::max(held_jump, regularised.velocities()[b].norm());
        }
    EXPECT_LT(held_jump, 0.5 * free_jump);
    on.regularisation_lambda = -1.0;
    EXPECT_THROW(on.validate(), InputError);
}
