#pragma once
// Corotational linear hexahedral FEM, integrated by linearised implicit Euler, one step per frame:
//   (M + dt C + dt^2 K) v' = M v + dt (f_ext - f_int(x)),   x' = x + dt v',
// with K = R K_0 R^T per element (R from the polar decomposition of F at the material centroid),
// Rayleigh damping C = alpha M + beta K, and a Jacobi-preconditioned conjugate-gradient solve warm
// started from v. The quasi-static mode instead solves K(x) dx = f_ext - f_int(x) by Newton
// iterations until the force residual meets the tolerance, so further frames change nothing.

#include "fem/hex_model.hpp"
#include "fem/multigrid.hpp"

#include <Eigen/Sparse>

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

namespace vox::fem {

struct SolverOptions {
    double dt_s = 0.01;
    double cg_tolerance = 1e-6;       ///< relative to the right-hand side's norm
    int cg_max_iterations = 200;
    double rayleigh_mass_per_s = 0.0; ///< alpha in C = alpha M + beta K, 1/s
    double rayleigh_stiffness_s = 0.0;///< beta, s
    bool quasi_static = false;
    int newton_max_iterations = 20;   ///< quasi-static mode
    /// Throws InputError naming the offending option.
    void validate() const;
};

struct StepStats {
    double step_ms = 0.0;
    int cg_iterations = 0;            ///< summed over Newton iterations in the quasi-static mode
    int newton_iterations = 0;
    double residual = 0.0;            ///< relative: CG residual (dynamic) or force residual (static)
    double kinetic_energy_j = 0.0;
    double elastic_energy_j = 0.0;
    double max_displacement_m = 0.0;
    bool converged = true;
};

class ImplicitSolver {
public:
    ImplicitSolver(const HexModel& model, const SolverOptions& options);

    /// Holds node `node` (dense index) along the axes whose bits are set in `axes` (1 x, 2 y, 4 z).
    void fix(std::uint32_t node, unsigned axes);
    /// Uniform acceleration of every mass, m/s^2 (gravity).
    void set_gravity(const Eigen::Vector3d& g) { m_gravity = g; }
    /// Extra external forces per node, N (point forces, tool contact); zero by default.
    [[nodiscard]] std::vector<Eigen::Vector3d>& external_forces() { return m_external; }

    /// Preconditions the CG solves with a multigrid V-cycle instead of Jacobi.
    void use_multigrid(std::unique_ptr<Multigrid> multigrid) { m_multigrid = std::move(multigrid); }

    StepStats step();

    [[nodiscard]] const std::vector<Eigen::Vector3d>& positions() const { return m_x; }
    [[nodiscard]] std::vector<Eigen::Vector3d>& positions() { return m_x; }
    [[nodiscard]] const std::vector<Eigen::Vector3d>& velocities() const { return m_v; }
    [[nodiscard]] std::vector<Eigen::Vector3d>& velocities() { return m_v; }
    /// Total linear momentum, kg m/s.
    [[nodiscard]] Eigen::Vector3d momentum() const;
    [[nodiscard]] std::size_t dof_count() const { return 3 * m_x.size(); }

private:
    /// Rotations, rotated stiffness into the matrix (scaled by `k_scale`, plus `m_scale` M),
    /// elastic forces and energy at the current positions.
    double assemble(double m_scale, double k_scale);
    Eigen::VectorXd external_force() const;
    void apply_constraints(Eigen::VectorXd& rhs);
    int solve(const Eigen::VectorXd& rhs, Eigen::VectorXd& x, double& residual);

    const HexModel& m_model;
    SolverOptions m_options;
    std::vector<Eigen::Vector3d> m_x, m_v, m_external;
    std::vector<unsigned char> m_fixed; ///< per dof
    Eigen::Vector3d m_gravity = Eigen::Vector3d::Zero();
    Eigen::SparseMatrix<double, Eigen::RowMajor> m_matrix;
    std::vector<int> m_slot;            ///< per element, 576 positions in m_matrix's values
    Eigen::VectorXd m_internal;         ///< internal forces, N, per dof
    std::unique_ptr<Multigrid> m_multigrid;
};

} // namespace vox::fem
