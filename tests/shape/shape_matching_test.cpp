#include "shape/shape_matching.hpp"

#include "fem/block_grid.hpp"

#include <Eigen/Geometry>
#include <gtest/gtest.h>

#include <random>

using namespace vox;
using namespace vox::shape;

namespace {

using test::block_grid;
using test::nodes_at;

struct Block {
    grid::BranchedGrid grid;
    fem::HexModel model;
    fem::ImplicitSolver solver;
    ShapeMatching* integrator = nullptr;
    Block(const Eigen::Vector3d& size_mm, int level, const fem::SolverOptions& options, const Settings& settings, int grid_levels = 4)
        : grid(block_grid(size_mm, grid_levels)), model(grid, level), solver(model, options)
    {
        auto sm = std::make_unique<ShapeMatching>(grid, model, settings);
        integrator = sm.get();
        solver.set_integrator(std::move(sm));
    }
};

fem::SolverOptions dynamic(double dt = 0.01)
{
    fem::SolverOptions o;
    o.dt_s = dt;
    return o;
}

} // namespace

TEST(ShapeMatching, ClustersCoverEveryNodeAndNestInTheirParents)
{
    Block b({8, 4, 4}, 1, dynamic(), Settings{});
    const auto& levels = b.integrator->clusters().levels();
    ASSERT_EQ(levels.size(), 3u); // levels 1, 2 and 3 of a grid built to 4
    EXPECT_EQ(levels[0].size(), b.model.elements().size());
    for (std::size_t l = 0; l < levels.size(); ++l) {
        SCOPED_TRACE(testing::Message() << "cluster level " << l);
        for (std::size_t j = 0; j < b.model.node_count(); ++j) EXPECT_GT(levels[l].particle_start[j + 1], levels[l].particle_start[j]);
        // Weighted rest offsets are centred.
        for (std::size_t c = 0; c < levels[l].size(); ++c) {
            Eigen::Vector3d s = Eigen::Vector3d::Zero();
            for (std::uint32_t m = levels[l].start[c]; m < levels[l].start[c + 1]; ++m) s += levels[l].weight[m] * levels[l].rest[m];
            EXPECT_LT(s.norm(), 1e-12);
        }
    }
    // 8 x 4 x 4 voxels of 1 mm: 4 x 2 x 2 elements at level 1 -> 2 x 1 x 1 at level 2 -> 1 at level 3.
    EXPECT_EQ(levels[1].size(), 2u);
    EXPECT_EQ(levels[2].size(), 1u);
    for (std::size_t c = 0; c < levels[0].size(); ++c) {
        // Every particle of a cluster is in its parent.
        const std::uint32_t parent = levels[0].parent[c];
        for (std::uint32_t m = levels[0].start[c]; m < levels[0].start[c + 1]; ++m) {
            bool found = false;
            for (std::uint32_t k = levels[1].start[parent]; k < levels[1].start[parent + 1]; ++k)
                found = found || levels[1].particle[k] == levels[0].particle[m];
            EXPECT_TRUE(found);
        }
    }
}

TEST(ShapeMatching, KappaOfAFullCubeIsMuTimesItsEdge)
{
    // tr K = (lambda + 4 mu) 8 d / 3 for the trilinear cube (the cluster header's formula), checked
    // on the condensed stiffness of a full element: kappa = mu d.
    Block b({4, 4, 4}, 1, dynamic(), Settings{}, 1);
    const grid::Lame lame = grid::lame_from_young_poisson(test::k_e, test::k_nu);
    const double d = 2e-3;
    for (double kappa : b.integrator->clusters().element_kappa()) EXPECT_NEAR(kappa, k_calibration * lame.mu * d, 1e-9 * lame.mu * d);
}

TEST(ShapeMatching, RigidMotionsAreReproducedExactly)
{
    Block b({8, 4, 4}, 1, dynamic(), Settings{});
    const Eigen::Matrix3d r = Eigen::AngleAxisd(0.9, Eigen::Vector3d(1, -2, 3).normalized()).toRotationMatrix();
    const Eigen::Vector3d t(0.02, -0.01, 0.005);
    for (auto& x : b.solver.positions()) x = r * x + t;
    // At rest, turned and moved: nothing moves, no energy.
    fem::StepStats s = b.solver.step();
    for (std::size_t j = 0; j < b.model.node_count(); ++j)
        EXPECT_LT((b.solver.positions()[j] - (r * b.model.rest_positions()[j] + t)).norm(), 1e-12); // round-off of the global solve
    EXPECT_LT(s.elastic_energy_j, 1e-28);
    // Moving uniformly: it goes on exactly (no damping).
    fem::SolverOptions o = dynamic();
    o.rayleigh_mass_per_s = 0.0;
    Block c({8, 4, 4}, 1, o, Settings{});
    const Eigen::Vector3d u(0.3, -0.1, 0.2);
    for (auto& v : c.solver.velocities()) v = u;
    for (int k = 0; k < 5; ++k) c.solver.step();
    for (std::size_t j = 0; j < c.model.node_count(); ++j) {
        EXPECT_LT((c.solver.positions()[j] - (c.model.rest_positions()[j] + 0.05 * u)).norm(), 1e-12);
        EXPECT_LT((c.solver.velocities()[j] - u).norm(), 1e-10); // 0.3 m/s to round-off
    }
}

TEST(ShapeMatching, GoalsAreTheBestRigidFitOfTheRestShape)
{
    Block b({4, 4, 4}, 1, dynamic(), Settings{}, 2);
    ShapeMatching& sm = *b.integrator;
    const ClusterLevel& level = sm.clusters().levels()[0];
    std::mt19937 rng(7);
    std::normal_distribution<double> noise(0.0, 2e-4);
    const Eigen::Matrix3d turn = Eigen::AngleAxisd(1.3, Eigen::Vector3d(0.3, 1, -0.5).normalized()).toRotationMatrix();
    std::vector<Eigen::Vector3d> p = b.model.rest_positions();
    for (auto& x : p) x = turn * x + Eigen::Vector3d(noise(rng), noise(rng), noise(rng)) + Eigen::Vector3d(1e-3, 0, 0);
    const std::size_t c = 3;
    std::vector<Eigen::Vector3d> goal;
    sm.goals(0, c, p, goal);
    const std::uint32_t begin = level.start[c], end = level.start[c + 1];
    // The brute-force fit: the centroid, and the rotation minimising the weighted squared distance
    // found by sampling rotations on a grid of rotation vectors around the identity and the best
    // of them refined by ever smaller random turns.
    Eigen::Vector3d centroid = Eigen::Vector3d::Zero();
    double total = 0.0;
    for (std::uint32_t m = begin; m < end; ++m) {
        centroid += level.weight[m] * p[level.particle[m]];
        total += level.weight[m];
    }
    centroid /= total;
    auto cost = [&](const Eigen::Matrix3d& rot) {
        double e = 0.0;
        for (std::uint32_t m = begin; m < end; ++m) e += level.weight[m] * (p[level.particle[m]] - centroid - rot * level.rest[m]).squaredNorm();
        return e;
    };
    Eigen::Matrix3d best = Eigen::Matrix3d::Identity();
    double best_cost = cost(best);
    const int steps = 24;
    for (int i = -steps; i <= steps; ++i)
        for (int j = -steps; j <= steps; ++j)
            for (int k = -steps; k <= steps; ++k) {
                const Eigen::Vector3d w = Eigen::Vector3d(i, j, k) * (M_PI / steps);
                if (w.norm() > M_PI) continue;
                const Eigen::Matrix3d rot = w.norm() == 0.0 ? Eigen::Matrix3d::Identity() : Eigen::AngleAxisd(w.norm(), w.normalized()).toRotationMatrix();
                const double e = cost(rot);
                if (e < best_cost) best_cost = e, best = rot;
            }
    std::uniform_real_distribution<double> unit(-1.0, 1.0);
    for (double radius = 0.1; radius > 1e-9; radius *= 0.7)
        for (int k = 0; k < 200; ++k) {
            const Eigen::Vector3d w(unit(rng), unit(rng), unit(rng));
            const Eigen::Matrix3d rot = Eigen::AngleAxisd(radius * w.norm(), w.normalized()).toRotationMatrix() * best;
            const double e = cost(rot);
            if (e < best_cost) best_cost = e, best = rot;
        }
    double ours = 0.0;
    for (std::uint32_t m = begin; m < end; ++m) {
        ours += level.weight[m] * (p[level.particle[m]] - goal[m - begin]).squaredNorm();
        EXPECT_LT((goal[m - begin] - (centroid + best * level.rest[m])).norm(), 1e-9);
    }
    EXPECT_LE(ours, best_cost * (1.0 + 1e-9));
}

TEST(ShapeMatching, TheAdaptiveSweepReachesTheFullSweepsPotential)
{
    // A cantilever held at one end, released under gravity: one step each way from the same state,
    // against the step's minimum found by a long classic sweep.
    const Eigen::Vector3d g(0, 0, -9.81);
    auto run = [&](const Settings& settings, double& phi, int& iterations, double& phi_start) {
        Block b({24, 4, 4}, 1, dynamic(), Settings{});
        for (std::uint32_t n : nodes_at(b.model, 0, -0.5e-3)) b.solver.fix(n, 7);
        b.solver.set_gravity(g);
        // A few steps first, the same for every sweep, so that the step measured starts in motion.
        for (int k = 0; k < 3; ++k) b.solver.step();
        auto sm = std::make_unique<ShapeMatching>(b.grid, b.model, settings);
        b.integrator = sm.get();
        b.solver.set_integrator(std::move(sm));
        // Where the step starts: each particle moved by its velocity and gravity alone, where Phi
        // is the clusters' energy only (the inertia term is zero there).
        std::vector<Eigen::Vector3d> y = b.solver.positions();
        for (std::size_t j = 0; j < y.size(); ++j)
            if (!b.solver.fixed_dofs()[3 * j])
                y[j] += 0.01 * (b.solver.velocities()[j] + 0.01 * g) / (1.0 + 0.01 * b.solver.options().rayleigh_mass_per_s);
        phi_start = b.integrator->energy(0, y);
        b.solver.step();
        phi = b.integrator->last_step().potential_j;
        iterations = b.integrator->last_step().total_iterations;
    };
    Settings full;
    full.adaptive = false;
    full.max_iterations = 20000;
    full.termination_rate = 1e-9;
    double best = 0.0, start = 0.0, phi = 0.0;
    int iterations = 0;
    run(full, best, iterations, start);
    // The adaptive and the classic sweep at the same budget and termination rate.
    Settings adaptive;
    adaptive.max_iterations = 2000;
    adaptive.termination_rate = 1e-4;
    run(adaptive, phi, iterations, start);
    const double removed = start - best;
    ASSERT_GT(removed, 0.0);
    Settings classic = adaptive;
    classic.adaptive = false;
    double phi_classic = 0.0;
    int iterations_classic = 0;
    run(classic, phi_classic, iterations_classic, start);
    std::printf("Phi removed by the step: adaptive %.4f, classic %.4f of the minimum's; iterations %d and %d\n", (start - phi) / removed,
                (start - phi_classic) / removed, iterations, iterations_classic);
    // Stated tolerance: the adaptive sweep's Phi within 2 % of what the classic sweep removes.
    EXPECT_LT(std::abs(phi - phi_classic), 0.02 * (start - phi_classic));
}

TEST(ShapeMatching, AKiloNewtonKickStaysBoundedAndSettles)
{
    // 1,000 N on one corner of a 0.13 g block held at one end, for one step: every goal is a rigid
    // placement of a rest shape, so the iteration cannot diverge whatever the load. The corner is
    // flung (the FEM's step would be too) and the block then swings back toward rest.
    fem::SolverOptions o = dynamic();
    o.rayleigh_mass_per_s = 5.0;
    Block b({8, 4, 4}, 1, o, Settings{});
    for (std::uint32_t n : nodes_at(b.model, 0, -0.5e-3)) b.solver.fix(n, 7);
    const std::uint32_t corner = nodes_at(b.model, 0, 7.5e-3).front();
    b.solver.external_forces()[corner] = Eigen::Vector3d(0, 0, 1000.0);
    b.solver.step();
    b.solver.external_forces()[corner].setZero();
    auto farthest = [&] {
        double d = 0.0;
        for (std::size_t j = 0; j < b.model.node_count(); ++j) d = std::max(d, (b.solver.positions()[j] - b.model.rest_positions()[j]).norm());
        return d;
    };
    const double kicked = farthest();
    double energy = 0.0;
    for (int k = 0; k < 300; ++k) {
        const fem::StepStats s = b.solver.step();
        ASSERT_TRUE(std::isfinite(s.kinetic_energy_j) && std::isfinite(s.elastic_energy_j));
        for (const auto& x : b.solver.positions()) ASSERT_TRUE(x.allFinite());
        energy = s.kinetic_energy_j + s.elastic_energy_j;
    }
    std::printf("kicked %.4g m, after 3 s %.4g m, energy %.3g J\n", kicked, farthest(), energy);
    EXPECT_LT(farthest(), 0.1 * kicked);
}

TEST(ShapeMatching, PlasticityKeepsASculptedShapeAndBoundsTheStrain)
{
    // As the FEM's test (tests/fem/solver_modes_test.cpp): push the free end of a clamped bar
    // sideways, then let go; an elastic bar springs back, a plastic one keeps part of the bend,
    // its plastic strain never beyond max_strain.
    double kept[2] = {0.0, 0.0};
    for (int plastic = 0; plastic < 2; ++plastic) {
        fem::SolverOptions o;
        o.quasi_static = true;
        Settings settings;
        settings.max_iterations = 20000;
        settings.termination_rate = 1e-10;
        Block b({16, 4, 4}, 1, o, settings, 2);
        fem::MaterialBehaviour behaviour;
        if (plastic) {
            behaviour.yield_strain = 0.002;
            behaviour.creep_per_s = 50.0;
            behaviour.max_strain = 0.004;
        }
        b.solver.set_materials({behaviour});
        for (std::uint32_t n : nodes_at(b.model, 0, -0.5e-3)) b.solver.fix(n, 7);
        const std::vector<std::uint32_t> end = nodes_at(b.model, 0, 15.5e-3);
        for (std::uint32_t n : end) b.solver.external_forces()[n] = Eigen::Vector3d(0, 1e-3, 0) / static_cast<double>(end.size());
        double loaded = 0.0;
        for (int k = 0; k < 30; ++k) loaded = b.solver.step().max_displacement_m;
        for (std::uint32_t n : end) b.solver.external_forces()[n].setZero();
        fem::StepStats s;
        // Static frames of shape matching end when an iteration gains too little: the last per
        // cent of a bend springs back over tens of frames (local-global iterations converge
        // linearly, slowly where rotations dominate), where the FEM's Newton solve takes one.
        for (int k = 0; k < 50; ++k) s = b.solver.step();
        kept[plastic] = s.max_displacement_m / loaded;
        for (std::uint32_t e = 0; e < b.model.elements().size(); ++e) EXPECT_LE(b.solver.plastic_strain(e).norm(), 0.004 * (1 + 1e-12));
        std::printf("%s: loaded %.4g mm, kept %.3f of it\n", plastic ? "plastic" : "elastic", loaded * 1e3, kept[plastic]);
    }
    EXPECT_LT(kept[0], 1e-3);
    EXPECT_GT(kept[1], 0.2);
}

TEST(ShapeMatching, ConstraintParticleGoalsFollowARigidMotionAndHoldAFaceParticleAtFourMuH)
{
    // SCPC's goals (shape_matching.hpp): a rigidly moved block is where its clusters want it, so
    // every particle's goal is its position; and a particle in the middle of a face of a full block
    // lies in four element clusters, each weighing it kappa = mu d (a full cube's corners weigh
    // kappa each): s = 4 mu d, the stiffness per face area d^2 the haptic snapshot uses 4 mu / d.
    Block b({8, 8, 8}, 1, dynamic(), Settings{}, 2);
    const Eigen::Matrix3d r = Eigen::AngleAxisd(0.7, Eigen::Vector3d(1, 2, 3).normalized()).toRotationMatrix();
    std::vector<Eigen::Vector3d> p = b.model.rest_positions();
    for (Eigen::Vector3d& x : p) x = r * x + Eigen::Vector3d(0.01, -0.02, 0.03);
    std::vector<Eigen::Vector3d> goal;
    std::vector<double> stiffness;
    b.integrator->particle_goals(p, {}, goal, stiffness);
    for (std::size_t j = 0; j < p.size(); ++j) EXPECT_LT((goal[j] - p[j]).norm(), 1e-12) << "particle " << j;
    const grid::Lame lame = grid::lame_from_young_poisson(test::k_e, test::k_nu);
    const double d = 2e-3;
    std::vector<std::uint32_t> face;
    for (std::uint32_t n = 0; n < b.model.node_count(); ++n)
        if ((b.model.rest_positions()[n] - Eigen::Vector3d(3.5e-3, 3.5e-3, 7.5e-3)).norm() < 1e-9) face.push_back(n); // voxel 0 is centred at 0
    ASSERT_EQ(face.size(), 1u);
    EXPECT_NEAR(stiffness[face.front()], 4.0 * lame.mu * d, 1e-9 * lame.mu * d);
    // Softened by water by the scale given.
    b.integrator->particle_goals(p, std::vector<double>(b.model.elements().size(), 0.25), goal, stiffness);
    EXPECT_NEAR(stiffness[face.front()], 0.25 * 4.0 * lame.mu * d, 1e-9 * lame.mu * d);
}

TEST(ShapeMatching, AConstraintParticleGoalIsTheMeanOfItsClustersBestFits)
{
    // A deformed block: each particle's goal is the stiffness-weighted mean of the goals its
    // clusters' optimal rotations give it (against goals() computed cluster by cluster).
    Block b({4, 4, 4}, 1, dynamic(), Settings{}, 2);
    std::mt19937 rng(7);
    std::uniform_real_distribution<double> jitter(-3e-4, 3e-4);
    std::vector<Eigen::Vector3d> p = b.model.rest_positions();
    for (Eigen::Vector3d& x : p) x += Eigen::Vector3d(jitter(rng), jitter(rng), jitter(rng));
    std::vector<Eigen::Vector3d> goal;
    std::vector<double> stiffness;
    b.integrator->particle_goals(p, {}, goal, stiffness);
    const ClusterLevel& l = b.integrator->clusters().levels().front();
    std::vector<Eigen::Vector3d> pull(p.size(), Eigen::Vector3d::Zero());
    std::vector<double> weight(p.size(), 0.0);
    for (std::size_t c = 0; c < l.size(); ++c) {
        std::vector<Eigen::Vector3d> g;
        b.integrator->goals(0, c, p, g);
        for (std::uint32_t m = l.start[c]; m < l.start[c + 1]; ++m) {
            pull[l.particle[m]] += l.weight[m] * g[m - l.start[c]];
            weight[l.particle[m]] += l.weight[m];
        }
    }
    for (std::size_t j = 0; j < p.size(); ++j) {
        EXPECT_NEAR(stiffness[j], weight[j], 1e-12 * weight[j]);
        EXPECT_LT((goal[j] - pull[j] / weight[j]).norm(), 1e-12) << "particle " << j;
    }
}
