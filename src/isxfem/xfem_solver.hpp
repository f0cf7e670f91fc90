#pragma once
// Corotational linear tetrahedra with Is-XFEM enrichment, integrated like the branched-grid solver
// (fem/implicit_solver.hpp): one linearised implicit Euler step per frame,
//   (M + dt C + dt^2 K) v' = M v + dt (f_ext - f_int(x)),   x' = x + dt v',
// Rayleigh damping C = alpha M + beta K, consistent mass, conjugate gradients warm started from v
// with Jacobi preconditioning (the scaling that keeps cut systems conditioned: docs/isxfem.md) or
// a given preconditioner (the warped factor of fem/rest_cholesky.hpp: each node turned by the mean
// rotation of what lies on its side, each enriched block as the jump between its node's two sides;
// after a cut it keeps its factor and solves the changed patch exactly beside it).
//
// State per dof block: a node's position (world m) or an enriched block's displacement (m).
// Rotations: a whole tetrahedron takes the rotational part of its deformation gradient; a cut one
// takes one per side, from the side's own linear field, the nodal positions x_i + (h - H_i) a_i
// (exact for k = 0, the linear part for k > 0), so the two pieces of a cut element can turn apart.

#include "isxfem/xfem_model.hpp"
#include "isxfem/xfem_operator.hpp"

#include "fem/pair_contact.hpp"
#include "fem/preconditioner.hpp"

#include <Eigen/Geometry>
#include <Eigen/SparseCore>

#include <array>
#include <memory>
#include <string>
#include <vector>

namespace vox::isxfem {

struct XfemOptions {
    double dt_s = 0.01;
    double cg_tolerance = 1e-6;  ///< relative to the Jacobi-scaled right-hand side
    int cg_max_iterations = 1000;
    double rayleigh_mass_per_s = 0.0;
    double rayleigh_stiffness_s = 0.0;
    /// The regularisation of the sculpting paper (section 4.3.2): enriched blocks whose volume
    /// ratio is below `regularisation_threshold` get lambda times the mean diagonal of the free
    /// standard dofs added to their diagonal in every solve (A + lambda I on those dofs) and the
    /// same times their velocity to the right-hand side: added inertia. Off by default: it
    /// conditions XFEM's near-node systems but slows the pieces' separation (docs/isxfem.md).
    double regularisation_lambda = 0.0;
    double regularisation_threshold = 1e-4;
    /// Throws InputError naming the offending option.
    void validate() const;
};

/// A force at a material point (tool contact): tetrahedron, barycentric coordinates and region
/// (XfemElement::region_at: its side of each cut, 0 when uncut), the force at the current positions
/// and its stiffness -d force / d x.
struct PointLoad {
    std::size_t tet = 0;
    std::array<double, 4> bary{};
    int side = 0;
    Eigen::Vector3d force_n = Eigen::Vector3d::Zero();
    Eigen::Matrix3d stiffness_n_per_m = Eigen::Matrix3d::Zero(); ///< symmetric, positive semidefinite
};

struct XfemStepStats {
    double step_ms = 0.0, assembly_ms = 0.0, solve_ms = 0.0;
    int cg_iterations = 0;
    double residual = 0.0; ///< relative, Jacobi-scaled
    bool converged = true;
    double kinetic_energy_j = 0.0;
};

class XfemSolver {
public:
    XfemSolver(const XfemModel& model, const XfemOptions& options);

    /// Preconditions the CG solves with `p` instead of Jacobi (null: back to Jacobi).
    void set_preconditioner(std::unique_ptr<fem::Preconditioner> p);
    [[nodiscard]] const char* preconditioner_name() const { return m_preconditioner ? m_preconditioner->name() : "Jacobi"; }
    /// Set when the preconditioner could not be built (a factor of a singular or nearly singular
    /// system) and Jacobi took over until the next cut; empty otherwise.
    [[nodiscard]] const std::string& fallback_note() const { return m_fallback_note; }

    /// Holds node `node` along the axes whose bits are set in `axes` (1 x, 2 y, 4 z).
    void fix(std::uint32_t node, unsigned axes);
    void set_gravity(const Eigen::Vector3d& g) { m_gravity = g; }
    /// After the model was cut: new enriched blocks start with zero displacement and velocity (a
    /// fresh cut moves nothing; a tetrahedron added to a crack whose nodes' blocks already moved
    /// takes their jump at once), newly cut tetrahedra turn both sides as they turned whole, and
    /// the matrix pattern is rebuilt.
    void model_changed();

    XfemStepStats step();

    /// Per dof block: positions of nodes (blocks < node_count) and enriched displacements.
    [[nodiscard]] const std::vector<Eigen::Vector3d>& state() const { return m_x; }
    [[nodiscard]] std::vector<Eigen::Vector3d>& velocities() { return m_v; }
    [[nodiscard]] const std::vector<Eigen::Vector3d>& velocities() const { return m_v; }
    /// Puts the state back to `x` and `v` (per dof block, as state() and velocities(); sizes as the
    /// model's blocks now): an undo. Throws std::invalid_argument when the sizes differ.
    void set_state(std::vector<Eigen::Vector3d> x, std::vector<Eigen::Vector3d> v);
    /// Forces at material points for the following steps (replacing the last ones), taken
    /// implicitly with their stiffness. Throws std::out_of_range for a tetrahedron that is not there.
    void set_point_loads(std::vector<PointLoad> loads);
    /// Contacts between material points the elements do not join (pieces, a crack's walls;
    /// fem/pair_contact.hpp) for the following steps, on dof blocks, replacing the previous ones:
    /// taken implicitly; those that would pull at the step's end are let go and the step solved
    /// again. Throws std::invalid_argument for a block out of range.
    void set_pair_contact(std::vector<fem::PairContact> pairs)
    {
        m_pairs.set(std::move(pairs), m_x);
        m_pair_in_matrix.assign(m_pairs.pairs().size(), 0); // step() puts them in its matrix
    }
    /// Contacts first..last-1's force at the current state (after a step: what they applied at its end).
    [[nodiscard]] fem::PairForceSum pair_contact_force(std::size_t first, std::size_t last) const { return m_pairs.force_sum(m_x, first, last); }
    [[nodiscard]] const fem::PairContacts& pair_contacts() const { return m_pairs; }
    /// The weights of the dof blocks of tetrahedron t (its nodes, then per cut their enriched
    /// blocks: psi_jc N_c) at the point with barycentric coordinates `n` in region `region`
    /// (XfemElement::region_at): the point moves by sum_a w_a x_a, and a force f there acts on
    /// block a as w_a f.
    [[nodiscard]] std::array<double, k_max_blocks> weights(std::size_t t, const std::array<double, 4>& n, int region) const;
    /// World position of the material point with barycentric coordinates `n` in tetrahedron t, in
    /// region `region` when the tetrahedron is cut (one cut: 0 where phi < 0, 1 where phi >= 0).
    [[nodiscard]] Eigen::Vector3d position(std::size_t t, const std::array<double, 4>& n, int region) const
    {
        return interpolate(t, n, region, m_x);
    }
    /// Velocity (m/s) of that material point.
    [[nodiscard]] Eigen::Vector3d velocity(std::size_t t, const std::array<double, 4>& n, int region) const
    {
        return interpolate(t, n, region, m_v);
    }
    [[nodiscard]] double kinetic_energy() const;
    [[nodiscard]] Eigen::Vector3d momentum() const;
    [[nodiscard]] std::size_t dof_count() const { return 3 * m_x.size(); }
    /// Enriched blocks regularised (their volume ratio below the threshold; none when lambda is 0).
    [[nodiscard]] std::size_t regularised_blocks() const { return m_regularised.size(); }

private:
    /// The per-block vectors `blocks` (positions or velocities) at a material point, as position().
    [[nodiscard]] Eigen::Vector3d interpolate(std::size_t t, const std::array<double, 4>& n, int region,
                                              const std::vector<Eigen::Vector3d>& blocks) const;
    /// `same_system`: the matrix and preconditioner of the previous solve, another right-hand side.
    int solve(const Eigen::VectorXd& rhs, Eigen::VectorXd& x, double& residual, bool same_system = false);

    const XfemModel& m_model;
    XfemOptions m_options;
    Eigen::Vector3d m_gravity = Eigen::Vector3d::Zero();
    std::vector<Eigen::Vector3d> m_x, m_v;
    std::vector<unsigned char> m_fixed;                    ///< per dof
    XfemOperator m_operator;
    std::unique_ptr<fem::Preconditioner> m_preconditioner;
    bool m_preconditioner_failed = false;   ///< Jacobi until the next cut
    std::string m_fallback_note;
    std::vector<Eigen::Quaterniond> m_block_rotation;
    std::vector<fem::JumpBlock> m_jumps; ///< every enriched block with its node
    std::vector<std::uint32_t> m_regularised; ///< enriched blocks below the volume-ratio threshold
    std::vector<PointLoad> m_loads;
    fem::PairContacts m_pairs;
    std::vector<unsigned char> m_pair_in_matrix; ///< per pair: this step's matrix holds its stiffness
    Eigen::VectorXd m_previous_v;
};

} // namespace vox::isxfem
