#pragma once
// Adaptive hierarchical shape matching (Tian, Yang, Guo and Prabhakaran 2015), stepping the nodes
// of the branched grid's model (`"solver": {"type": "shape_matching"}`).
//
// A step minimises the incremental potential of the particles,
//   Phi(p) = sum_j m_j / (2 dt^2) |p_j - x_j - dt v_j|^2 - f . p + sum_c E_c(p) + contact,
// E_c the clusters' shape-matching energies (shape/cluster_hierarchy.hpp), by the paper's shape
// matching iterations: every cluster fits its best rotation and centroid (its goals g), then each
// particle moves to the minimiser of its own terms with the goals fixed (the paper's averaging of
// overlapping clusters, weighted by stiffness and inertia; tool and pair contacts taken implicitly
// by their stiffness). At a fixed point the goals' pull is the exact gradient of the clusters'
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
// - subdivision: below the top level only the children of clusters whose deformation
//   (energy / rest moment, a squared strain) exceeds `subdivision_strain`^2 iterate;
// - origination: a level whose first iteration last step already met the termination condition is
//   skipped for the next k_origination_skip steps (the step starts at a finer level).
// Without "adaptive" every level and cluster iterates until the termination condition (classic
// hierarchical shape matching), for comparison.

#include "fem/node_integrator.hpp"
#include "shape/cluster_hierarchy.hpp"

#include <Eigen/Geometry>

#include <string>
#include <vector>

namespace vox::shape {

struct Settings {
    int coarse_levels = 2;           ///< cluster levels above the simulated one
    bool adaptive = true;
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
    double potential_j = 0.0;         ///< Phi at the end (without the contacts' potential)
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

    static constexpr int k_origination_skip = 8;
    /// Iterations of one level in one cycle at most.
    static constexpr int k_cycle_iterations = 10;

private:
    /// Fits the clusters of `level` that `active` flags at p (stiffness times `scale` per cluster,
    /// none: 1): fills their members' goals and their energies; returns their energy, J.
    double fit(std::size_t level, const std::vector<Eigen::Vector3d>& p, const std::vector<double>& scale,
               const std::vector<unsigned char>& active);

    const fem::HexModel* m_model;
    Settings m_settings;
    ClusterHierarchy m_clusters;
    std::vector<std::vector<Eigen::Quaterniond>> m_rotation; ///< per level and cluster: warm start
    std::vector<std::vector<Eigen::Vector3d>> m_goal;        ///< per level and member
    std::vector<std::vector<double>> m_energy;               ///< per level and cluster, J
    std::vector<std::vector<unsigned char>> m_active;        ///< per level and cluster
    std::vector<std::vector<std::uint32_t>> m_member_cluster; ///< per level and member: its cluster
    std::vector<int> m_skip;                                 ///< per level: steps left to skip (origination)
    StepReport m_report;
};

} // namespace vox::shape
