#pragma once
// Adaptive hierarchical shape matching (Tian, Yang, Guo and Prabhakaran 2015), stepping the nodes
// of the branched grid's model (`"solver": {"type": "shape_matching"}`).
//
// A step minimises the incremental potential of the particles,
//   Phi(p) = sum_j m_j / (2 dt^2) |p_j - x_j - dt v_j|^2 - f . p + sum_c E_c(p) + contact,
// E_c the clusters' shape-matching energies (shape/cluster_hierarchy.hpp), by the paper's shape
// matching iterations: every cluster fits its best rotation and centroid (its goals g), then the
// particles move to the minimiser of Phi with the rotations fixed: on the simulated level by the
// global step (shape/global_step.hpp; "global_step": false for the paper's averaging), on coarser
// levels, and everywhere without it, particle by particle with the goals fixed (the paper's
// averaging of overlapping clusters, weighted by stiffness and inertia). Tool and pair contacts
// are taken implicitly by their stiffness. At a fixed point the goals' pull is the exact gradient of the clusters'
// energy (the centroid and rotation are optimal), so the step converges to the implicit Euler
// step of the shape-matching energy. Velocities are what the step moved, v = (p - x) / dt. Since
// every goal is a rigid placement of a rest shape, no input (a 1,000 N kick) makes the iteration
// diverge: the paper's unconditional stability.
//
// The hierarchy: iterations start on the coarsest clusters (which spread a load over their whole
// region in one iteration) and go finer. Phi is always that of the simulated level's clusters: a
// coarse iteration is a proposal, kept when it lowers Phi (a coarse cluster is stiffer than the
// fine ones it spans; converged alone it would pull the object to its own, coarser minimum, which
// the fine iterations then undo slowly). The paper's three conditions decide the work:
// - termination: a level stops once an iteration lowers Phi by less than `termination_rate` of
//   the energy it holds (inertia and clusters);
// - subdivision: below the top level, from the second cycle on, only the children of clusters
//   whose deformation (energy / rest moment, a squared strain) exceeds `subdivision_strain`^2
//   iterate (the first cycle starts before any load has deformed anything; a cycle that stalls
//   so is followed by one of every cluster before the step ends);
// - origination: a level whose first iteration already met the termination condition is skipped
//   for the next k_origination_skip steps, twice as long each time it fails again in a row, up to
//   k_origination_skip_max (the step starts at a finer level).
// With the global step the coarse levels propose no moves (it carries a load across the object
// in one iteration, where their proposals cost more than they gained: 27 against 39 ms a step on
// data/scenes/press_and_cut.json): they are fitted once a cycle for the subdivision condition,
// so that only the simulated level's clusters under deformed coarse ones are fitted again.
// Without "adaptive" every level and cluster iterates until the termination condition (classic
// hierarchical shape matching), for comparison.

#include "fem/node_integrator.hpp"
#include "shape/cluster_hierarchy.hpp"
#include "shape/global_step.hpp"

#include <Eigen/Geometry>

#include <string>
#include <vector>

namespace vox::shape {

struct Settings {
    int coarse_levels = 2;           ///< cluster levels above the simulated one
    bool adaptive = true;
    /// The simulated level's iterations solve the global step (shape/global_step.hpp) instead of
    /// the paper's averaging particle by particle.
    bool global_step = true;
    int max_iterations = 60;         ///< shape-matching iterations a step, all levels together
    double termination_rate = 0.01;  ///< a level stops when an iteration lowers Phi by less than this share of its energy
    double subdivision_strain = 1e-4;///< finer clusters iterate under parents deformed beyond this strain
};

/// What the last step did, level by level (index 0: the simulated level).
struct StepReport {
    std::vector<int> iterations;      ///< per level
    std::vector<std::size_t> active;  ///< clusters iterated at the level's last iteration
    int total_iterations = 0;
    bool converged = false;           ///< a whole cycle met the termination condition
    double initial_potential_j = 0.0; ///< Phi where the step started (each particle moved by its velocity and the loads)
    double potential_j = 0.0;         ///< Phi at the end
    double elastic_energy_j = 0.0;    ///< the simulated level's clusters' energy at the end
};

class ShapeMatching final : public fem::NodeIntegrator {
public:
    /// Steps `model`'s nodes (level L of `grid`) with clusters at L and up to settings.coarse_levels coarser levels.
    ShapeMatching(const grid::BranchedGrid& grid, const fem::HexModel& model, const Settings& settings);

    fem::StepStats step(fem::ImplicitSolver& solver) override;
    [[nodiscard]] std::string description() const override;

    [[nodiscard]] const ClusterHierarchy& clusters() const { return m_clusters; }
    [[nodiscard]] const StepReport& last_step() const { return m_report; }
    [[nodiscard]] const Settings& settings() const { return m_settings; }

    /// Goal positions of cluster `c` of level `level` for particle positions `p` (its members'
    /// order), with its warm-start rotation updated: exposed for tests.
    void goals(std::size_t level, std::size_t c, const std::vector<Eigen::Vector3d>& p, std::vector<Eigen::Vector3d>& out);
    /// The clusters' shape-matching energy of level `level` at positions p, J (goals fitted at p).
    double energy(std::size_t level, const std::vector<Eigen::Vector3d>& p);

    /// Stable constraint particle coupling (docs/shape-matching.md): where the simulated level's
    /// clusters, fitted at positions p, put each particle (the mean of its goals weighted by their
    /// stiffness) and how stiffly (the sum of those weights, N/m; cluster c's times `scale[c]`,
    /// the water's softening, when given). A particle in no cluster keeps p, with stiffness 0.
    void particle_goals(const std::vector<Eigen::Vector3d>& p, const std::vector<double>& scale, std::vector<Eigen::Vector3d>& goal,
                        std::vector<double>& stiffness) const;

    static constexpr int k_origination_skip = 8;
    static constexpr int k_origination_skip_max = 64;
    /// Iterations of one level in one cycle at most.
    static constexpr int k_cycle_iterations = 10;
    /// A global step with contacts stops its conjugate gradients here (residual relative to its
    /// start, or iterations): the local-global iterations around it correct the rest. Solved to
    /// 1e-8 a tool pressing data/scenes/cylinder.json took 314 ms a step.
    static constexpr double k_contact_tolerance = 1e-3;
    static constexpr int k_contact_iterations = 10;

private:
    /// Fits the clusters of `level` that `active` flags at p (stiffness times `scale` per cluster,
    /// none: 1): fills their members' goals and their energies; returns their energy, J.
    double fit(std::size_t level, const std::vector<Eigen::Vector3d>& p, const std::vector<double>& scale,
               const std::vector<unsigned char>& active);

    /// Plasticity (the materials' "plasticity", as the FEM's): the simulated level's rest shapes
    /// stretched by each element's plastic strain, at a step's start ...
    void plastic_rest(const fem::ImplicitSolver& solver);
    /// ... and the plastic strain crept toward the elastic excess at its end (positions p).
    void creep(fem::ImplicitSolver& solver, const std::vector<Eigen::Vector3d>& p, double dt);

    const fem::HexModel* m_model;
    Settings m_settings;
    ClusterHierarchy m_clusters;
    std::vector<std::vector<Eigen::Quaterniond>> m_rotation; ///< per level and cluster: warm start
    std::vector<std::vector<Eigen::Vector3d>> m_goal;        ///< per level and member
    std::vector<std::vector<double>> m_energy;               ///< per level and cluster, J
    std::vector<std::vector<Eigen::Vector3d>> m_centroid;    ///< per level and cluster: of the last fit
    std::vector<std::vector<Eigen::Vector3d>> m_rest;        ///< per level and member: rest offsets now (plastic ones stretched)
    GlobalStep m_global;
    std::vector<std::vector<unsigned char>> m_active;        ///< per level and cluster
    std::vector<std::vector<std::uint32_t>> m_member_cluster; ///< per level and member: its cluster
    std::vector<int> m_skip;                                 ///< per level: steps left to skip (origination)
    std::vector<int> m_backoff;                              ///< per level: steps the next skip lasts
    StepReport m_report;
};

} // namespace vox::shape
