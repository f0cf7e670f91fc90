#pragma once
// The clusters of adaptive hierarchical shape matching (Tian, Yang, Guo and Prabhakaran 2015) on
// the branched grid: the particles are the nodes of the simulated level's model (a superimposed
// element has its own nodes, so disconnected material in one cell stays apart), each element of
// that level is a cluster of its eight corners, and each element of a coarser level is a cluster
// of every particle of the model elements below it. The grid's levels are the paper's cube-mesh
// hierarchy, its superimposed elements included, so the hierarchy needs no structure of its own.
//
// Stiffness. A cluster's energy is E_c = 1/2 sum_j w_j |p_j - g_j|^2 (g the goal positions: the
// rest shape turned by the best rotation and moved to the current centroid). For a full cube of
// side d under a uniform strain eps, sum_j |eps q_j|^2 = 2 d^2 |eps|_F^2, so weights of kappa on
// each corner store kappa d^2 |eps|^2 where linear elasticity stores d^3 (mu |eps|^2 + lambda/2
// tr(eps)^2): kappa = mu d matches the shear part (shape matching has no volume term). An element's
// mu is read from the trace of its condensed stiffness, tr K = (lambda + 4 mu) 8 d / 3 for a full
// trilinear cube (so partial and mixed elements get their share), and its corners weigh by their
// share of its mass. The factor k_calibration scales kappa so that a cantilever sags as the FEM
// does at the same E (docs/shape-matching.md has the measurement).

#include "fem/hex_model.hpp"
#include "grid/branched_grid.hpp"

#include <Eigen/Core>

#include <cstdint>
#include <vector>

namespace vox::shape {

/// kappa = k_calibration mu d (see above): measured on a cantilever against the FEM, the same
/// sag under gravity at level 1 (tests/shape/calibration_test.cpp; docs/shape-matching.md).
inline constexpr double k_calibration = 1.0;

/// One level of clusters: members are (particle, weight, rest offset from the cluster's weighted
/// rest centroid); clusters index their members through `start`, particles theirs through
/// `particle_start`.
struct ClusterLevel {
    int grid_level = 0;
    std::vector<std::uint32_t> start;    ///< per cluster, into the members; one more than clusters
    std::vector<std::uint32_t> particle; ///< per member
    std::vector<double> weight;          ///< per member, N/m (kappa times the corner's share)
    std::vector<Eigen::Vector3d> rest;   ///< per member, m, world frame
    std::vector<double> rest_moment;     ///< per cluster: sum_j w_j |rest_j|^2, N m
    std::vector<std::uint32_t> parent;   ///< per cluster: its cluster one level coarser (grid::no_index at the top)
    std::vector<std::uint32_t> particle_start;  ///< per particle, into particle_member; one more than particles
    std::vector<std::uint32_t> particle_member; ///< members grouped by particle
    [[nodiscard]] std::size_t size() const { return start.empty() ? 0 : start.size() - 1; }
    /// The weighted centroid of cluster c's particles at positions `x` (per particle).
    [[nodiscard]] Eigen::Vector3d centroid(std::size_t c, const std::vector<Eigen::Vector3d>& x) const
    {
        Eigen::Vector3d sum = Eigen::Vector3d::Zero();
        double total = 0.0;
        for (std::uint32_t m = start[c]; m < start[c + 1]; ++m) {
            sum += weight[m] * x[particle[m]];
            total += weight[m];
        }
        return sum / total;
    }
};

class ClusterHierarchy {
public:
    /// Clusters of `model` (level L of `grid`) and of up to `coarse_levels` coarser levels
    /// (fewer when the grid has fewer). levels()[0] is the model's own.
    ClusterHierarchy(const grid::BranchedGrid& grid, const fem::HexModel& model, int coarse_levels);

    [[nodiscard]] const std::vector<ClusterLevel>& levels() const { return m_levels; }
    [[nodiscard]] std::size_t particle_count() const { return m_particles; }
    /// kappa of each model element (cluster of level 0), N/m, before its water softens it.
    [[nodiscard]] const std::vector<double>& element_kappa() const { return m_kappa; }

    /// The shear modulus an element's condensed stiffness amounts to, Pa (from its trace; see the
    /// header comment), for an element of edge `d` m whose material has ratio lambda / mu `ratio`.
    [[nodiscard]] static double element_mu(const fem::HexElement& element, double d, double ratio);

private:
    std::size_t m_particles = 0;
    std::vector<double> m_kappa;
    std::vector<ClusterLevel> m_levels;
};

} // namespace vox::shape
