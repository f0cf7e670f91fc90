#pragma once
// Corotational linear hexahedral FEM, integrated by linearised implicit Euler, one step per frame:
//   (M + dt C + dt^2 K) v' = M v + dt (f_ext - f_int(x)),   x' = x + dt v',
// with K = R K_0 R^T per element (R the rotational part of F at the material centroid), Rayleigh
// damping C = alpha M + beta K, and a preconditioned conjugate-gradient solve warm started from v
// (Jacobi unless a preconditioner is given). The quasi-static mode instead solves K(x) dx = f_ext - f_int(x) by Newton
// iterations until the force residual meets the tolerance, so further frames change nothing.

#include "fem/hex_model.hpp"
#include "fem/pair_contact.hpp"
#include "fem/preconditioner.hpp"
#include "fem/volume_correction.hpp"

#include <Eigen/Sparse>

#include <array>
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

namespace vox::fem {

class NodeIntegrator;

struct SolverOptions {
    double dt_s = 0.01;
    double cg_tolerance = 1e-6;       ///< relative to the right-hand side's norm
    int cg_max_iterations = 200;
    double rayleigh_mass_per_s = 0.0; ///< alpha in C = alpha M + beta K, 1/s
    double rayleigh_stiffness_s = 0.0;///< beta, s
    bool quasi_static = false;
    /// Row-sum (lumped) mass instead of the consistent mass: the same total mass and momentum, a
    /// diagonal M, and a much better conditioned implicit system (consistent hexahedral mass alone
    /// spreads its eigenvalues 27-fold).
    bool lumped_mass = true;
    /// Never assemble the system matrix: apply it element by element (SOFA's way), with the Jacobi
    /// preconditioner. (With the warped factor the solver already multiplies element by element
    /// and assembles only when the factor is taken again.)
    bool matrix_free = false;
    int newton_max_iterations = 30;   ///< quasi-static mode, and dynamic steps solved fully (newton_step)
    /// Throws InputError naming the offending option.
    void validate() const;
};

/// What a material does beyond linear elasticity (index = grid material index).
struct MaterialBehaviour {
    /// Müller & Gross 2004 plasticity: when the elastic strain's Frobenius norm exceeds
    /// yield_strain, creep_per_s * dt of it turns plastic each step; the plastic strain's norm
    /// stays at most max_strain. yield_strain 0: elastic.
    double yield_strain = 0.0;
    double creep_per_s = 0.0;
    double max_strain = 0.0;
    /// At water content w, stiffness and yield are scaled by 1 - (1 - ratio) w.
    double wet_stiffness_ratio = 1.0;
    double wet_yield_ratio = 1.0;
    [[nodiscard]] bool plastic() const { return yield_strain > 0.0; }
};

struct StepStats {
    double step_ms = 0.0;
    double assembly_ms = 0.0;         ///< rotations, matrix and forces (every Newton iteration summed)
    double solve_ms = 0.0;            ///< preconditioner set-up and CG
    int cg_iterations = 0;            ///< summed over Newton iterations in the quasi-static mode
    int newton_iterations = 0;        ///< static mode, and dynamic steps solved fully (newton_step)
    double residual = 0.0;            ///< relative: CG residual (dynamic) or force residual (static)
    double kinetic_energy_j = 0.0;
    double elastic_energy_j = 0.0;
    double max_displacement_m = 0.0;
    bool converged = true;
    int substeps = 0;                 ///< dynamic: halvings taken because a step gained energy
    /// A step gained energy even solved fully at 1/32 of dt, and had the excess taken out
    /// (project_energy): the session goes on, the frame says so.
    bool energy_projected = false;
};

/// Penalty contact (a tool against the surface) gathered on one node, world frame.
struct NodeContact {
    std::uint32_t node = 0;                                   ///< dense node index
    Eigen::Vector3d force_n = Eigen::Vector3d::Zero();        ///< at the positions it was computed at
    Eigen::Matrix3d stiffness_n_per_m = Eigen::Matrix3d::Zero(); ///< -d force / d position: symmetric, positive semidefinite
};

class ImplicitSolver {
public:
    /// `same_mesh`: a solver of a model that may have the same elements on the same nodes (the
    /// model before a cut); when it has, its incidence and matrix pattern are reused.
    ImplicitSolver(const HexModel& model, const SolverOptions& options, const ImplicitSolver* same_mesh = nullptr);
    ~ImplicitSolver();
    ImplicitSolver(ImplicitSolver&&) noexcept;

    /// Holds node `node` (dense index) along the axes whose bits are set in `axes` (1 x, 2 y, 4 z).
    void fix(std::uint32_t node, unsigned axes);
    /// Whether fix() holds `node` on all three axes.
    [[nodiscard]] bool held(std::uint32_t node) const { return m_held[3 * node] && m_held[3 * node + 1] && m_held[3 * node + 2]; }
    /// Axis `axis` (0..2) of `node` is held by fix().
    [[nodiscard]] bool held_axis(std::uint32_t node, int axis) const { return m_held[3 * node + static_cast<std::size_t>(axis)] != 0; }
    /// Nodes at rest held until woken (per node, 1: asleep), on top of those fix() holds; their
    /// velocities are zeroed. An empty vector wakes every node.
    void set_asleep(const std::vector<unsigned char>& asleep);
    /// Uniform acceleration of every mass, m/s^2 (gravity).
    void set_gravity(const Eigen::Vector3d& g) { m_gravity = g; }
    /// Where each node would be after a step of dt moving freely, x + dt (v + dt g), held dofs
    /// where they are: what contact looks ahead to (a piece at rest on a table falls g dt^2 into
    /// it in a step; its velocity alone says it stays).
    [[nodiscard]] std::vector<Eigen::Vector3d> free_step_positions(double dt) const;
    /// Extra external forces per node, N (point forces, tool contact); zero by default.
    [[nodiscard]] std::vector<Eigen::Vector3d>& external_forces() { return m_external; }

    /// Contact forces for the following steps, replacing the previous ones. They are taken
    /// implicitly: at positions x the force is force_n - stiffness (x - x_now), so a stiff penalty
    /// stays stable at any dt (an explicit penalty force on a light node explodes).
    void set_contact(std::vector<NodeContact> contact);
    [[nodiscard]] const std::vector<NodeContact>& contact() const { return m_contact; }
    /// Contacts between material points the elements do not join (pieces, the walls of a cut;
    /// fem/pair_contact.hpp) for the following steps, replacing the previous ones; blocks are
    /// nodes. Taken implicitly, as set_contact's. Throws std::invalid_argument for a node out of range.
    void set_pair_contact(std::vector<PairContact> pairs)
    {
        m_pairs.set(std::move(pairs), m_x);
        m_pair_in_matrix.assign(m_pairs.pairs().size(), 0);
        m_matrix_current = false; // the matrix holds the old pairs
    }
    /// Pair contacts first..last-1's force at the current positions (after a step: what they
    /// applied at its end).
    [[nodiscard]] PairForceSum pair_contact_force(std::size_t first, std::size_t last) const { return m_pairs.force_sum(m_x, first, last); }
    /// The pair contacts of the last step (those it let go: stiffness 0).
    [[nodiscard]] const PairContacts& pair_contacts() const { return m_pairs; }

    /// Preconditions the CG solves with `p` instead of Jacobi (null: back to Jacobi).
    /// Throws InputError in the matrix-free mode, which has no matrix to build one from.
    void set_preconditioner(std::unique_ptr<Preconditioner> p);
    /// After a cut that kept every node of the model (same numbering, same holds, same dt): goes on
    /// with `previous`'s preconditioner, told which node blocks changed (it may patch them instead
    /// of being built anew: a drill taking a voxel a frame would otherwise refactor every frame).
    void adopt_preconditioner(ImplicitSolver& previous, const std::vector<std::uint32_t>& changed_nodes);
    /// Set when the given preconditioner could not be built and Jacobi took over; empty otherwise.
    [[nodiscard]] const std::string& fallback_note() const { return m_fallback_note; }
    /// Steps the nodes by `integrator` instead of the corotational FEM (null: back to the FEM).
    void set_integrator(std::unique_ptr<NodeIntegrator> integrator);
    [[nodiscard]] const NodeIntegrator* integrator() const { return m_integrator.get(); }

    // What an integrator reads (fem/node_integrator.hpp).
    [[nodiscard]] const HexModel& model() const { return m_model; }
    [[nodiscard]] const SolverOptions& options() const { return m_options; }
    /// Per dof: held by fix() or asleep.
    [[nodiscard]] const std::vector<unsigned char>& fixed_dofs() const { return m_fixed; }
    [[nodiscard]] const Eigen::Vector3d& gravity() const { return m_gravity; }
    /// Adds the tools' and pairs' contact forces at positions `at` to `f` (per dof), each the
    /// linearised penalty it was set with.
    void add_contact_forces(const std::vector<Eigen::Vector3d>& at, Eigen::VectorXd& f) const;
    /// Lets go of the pair contacts that would pull at positions `at` and lets in the waiting ones
    /// pressed in there (PairContacts::settle); returns how many changed. An integrator ends its
    /// step with this, solving again while it changes something, as the FEM's step does.
    std::size_t settle_pairs(const std::vector<Eigen::Vector3d>& at) { return m_pairs.settle(at); }
    /// The tools' and pairs' contact potential at positions `at`, J, relative to where they were
    /// set (-f d + d^T K d / 2 for each, d the move since).
    [[nodiscard]] double contact_potential(const std::vector<Eigen::Vector3d>& at) const;
    /// Per node, the contacts' stiffness on it alone (N/m, 3 x 3: the tool's, plus the node's own
    /// block of each pair's): what an iteration over single nodes takes implicitly.
    [[nodiscard]] std::vector<Eigen::Matrix3d> contact_node_stiffness() const;

    StepStats step();

    /// How the nodes would move in one step (the quasi-static mode: at equilibrium) under extra
    /// forces `load` (per node, N), the tools' contact springs left out: (m M + k K)^-1 load
    /// scaled to a displacement, m (tied nodes following, held ones still). The condensed
    /// compliance at a contact is load^T response(load). Empty with an integrator (no FEM
    /// system) or when the solve does not converge (a free object in the quasi-static mode).
    [[nodiscard]] std::vector<Eigen::Vector3d> response(const std::vector<Eigen::Vector3d>& load);

    [[nodiscard]] const std::vector<Eigen::Vector3d>& positions() const { return m_x; }
    [[nodiscard]] std::vector<Eigen::Vector3d>& positions()
    {
        m_element_pass_current = false; // the caller may move nodes
        return m_x;
    }
    [[nodiscard]] const std::vector<Eigen::Vector3d>& velocities() const { return m_v; }
    [[nodiscard]] std::vector<Eigen::Vector3d>& velocities() { return m_v; }
    /// Total linear momentum, kg m/s.
    [[nodiscard]] Eigen::Vector3d momentum() const;
    [[nodiscard]] std::size_t dof_count() const { return 3 * m_x.size(); }

    /// Inelastic behaviour per material; plastic state is kept only when some material is plastic.
    void set_materials(std::vector<MaterialBehaviour> behaviour);
    /// Water content of an element in [0, 1] (clamped); softens it by its material's law.
    void set_water(std::uint32_t element, double water);
    [[nodiscard]] double water(std::uint32_t element) const { return m_water.empty() ? 0.0 : m_water[element]; }
    /// The stiffness scale of an element now: its material's wet law at its water content (1 dry).
    [[nodiscard]] double stiffness_scale(std::uint32_t element, std::int32_t material) const
    {
        if (m_behaviour.empty() || static_cast<std::size_t>(material) >= m_behaviour.size()) return 1.0;
        return 1.0 - (1.0 - m_behaviour[static_cast<std::size_t>(material)].wet_stiffness_ratio) * water(element);
    }
    /// Plastic strain of an element (index-aligned frame); zero without plasticity.
    [[nodiscard]] Eigen::Matrix3d plastic_strain(std::uint32_t element) const
    {
        return m_plastic.empty() ? Eigen::Matrix3d::Zero() : m_plastic[element];
    }
    [[nodiscard]] bool has_plasticity() const { return !m_plastic.empty(); }
    /// Per material, as set_materials() gave it (empty before).
    [[nodiscard]] const std::vector<MaterialBehaviour>& behaviour() const { return m_behaviour; }
    /// Sets an element's plastic strain (carried over when a cut rebuilds the model); ignored
    /// without plasticity.
    void set_plastic_strain(std::uint32_t element, const Eigen::Matrix3d& strain)
    {
        if (!m_plastic.empty()) m_plastic[element] = strain;
    }

    /// Elastic energy at the current positions, J (updates the element rotations).
    double elastic_energy();

private:
    /// Node incidence of the elements and, unless matrix-free, the matrix pattern.
    void build_pattern();
    /// Fills m_run_groups from the incidence (greedy: each run in the first group none of whose
    /// runs shares a node with it).
    void group_runs();
    /// Calls f(elements, count) for the active elements of every run, up to four at a time (their
    /// indices, in order), the runs of one group of m_run_groups in parallel: f may add into the
    /// elements' nodes, since no two elements running at once share one.
    template <typename F>
    void for_each_element_by_runs(F&& f) const;
    /// Whether the two models have the same elements on the same nodes.
    [[nodiscard]] static bool same_connectivity(const HexModel& a, const HexModel& b);
    /// What an assembly produces beyond the element rotations, elastic forces and energy.
    enum class Output { forces, diagonal, matrix };
    /// Element rotations, elastic forces (m_internal) and energy at the current positions; then
    /// the diagonal of the system matrix m_scale M + k_scale K(x), or the whole matrix (m_matrix).
    double assemble(double m_scale, double k_scale, Output output);
    /// What a system solve needs assembled: the matrix only when there is no matrix-free product
    /// to use or the preconditioner will read it.
    [[nodiscard]] Output system_output() const;
    /// Adds the plastic forces of element e to `force` (local frame), letting its plastic strain
    /// creep first when a step starts; returns the energy correction, J.
    double plastic_correction(std::size_t e, const Vector24d& u, Vector24d& force);
    /// The volume correction of element e at deformation gradient `f` and corotational rotation
    /// `rotation` (index-aligned frame; fem/volume_correction.hpp): adds its forces into `forces`
    /// (per dof), keeps its Hessian's positive part for the system, returns its energy, J.
    double add_volume_correction(std::size_t e, const Eigen::Matrix3d& f, const Eigen::Matrix3d& rotation, double* forces);
    /// out = M v (lumped or consistent, with the added mass floor).
    void mass_times(const std::vector<Eigen::Vector3d>& v, Eigen::VectorXd& out) const;
    /// Adds sign times the step's stiffness of the pair contacts `which` (all when null) to the
    /// assembled matrix, those whose blocks its pattern joins (fem::add_to_matrix); adding marks
    /// them in m_pair_in_matrix (multiply() then leaves them out), taking away only the marked.
    void pairs_into_matrix(double sign, const std::vector<std::size_t>* which = nullptr);
    Eigen::VectorXd external_force() const;
    void apply_constraints(Eigen::VectorXd& rhs);
    /// The system's product on the free space (ties applied: T^T A T p).
    void multiply(const Eigen::VectorXd& p, Eigen::VectorXd& out) const;
    /// The whole system's product, every node its own.
    void multiply_full(const Eigen::VectorXd& p, Eigen::VectorXd& out) const;
    /// Tied nodes take the values of the coarse nodes they follow (T v on the free entries).
    void expand(Eigen::VectorXd& v) const;
    /// Tied nodes' entries handed to the nodes they follow (T^T v), theirs set to zero.
    void condense(Eigen::VectorXd& v) const;
    void multiply_matrix(const Eigen::VectorXd& p, Eigen::VectorXd& out) const;
    void multiply_element_wise(const Eigen::VectorXd& p, Eigen::VectorXd& out) const;
    void update_node_rotations();
    /// Flags the elements with a degree of freedom free to move (m_active); the others are
    /// skipped by every element loop.
    void update_active();
    /// `same_system`: the matrix and preconditioner of the previous solve, another right-hand side.
    /// `tolerance`: CG's relative tolerance when not the scene's (a Newton iteration's own).
    int solve(const Eigen::VectorXd& rhs, Eigen::VectorXd& x, double& residual, bool same_system = false, double tolerance = 0.0);
    [[nodiscard]] double kinetic_energy() const;
    /// One linearised implicit Euler step of `dt`; returns the external forces' work over it and
    /// sets `energy_before` to the kinetic plus elastic energy at its start.
    double linear_step(double dt, StepStats& s, double& energy_before);
    /// The same step solved fully: Newton on implicit Euler's incremental potential
    /// Phi(v) = 1/2 (1 + alpha dt) v'Mv - v'M v0 + Psi(x0 + dt v) + U(x0 + dt v) (Psi the
    /// corotational elastic energy, U gravity, loads and contact), each iteration re-rotating the
    /// elements, with a backtracking line search on Phi, as optimisation-based integrators do.
    /// The Rayleigh stiffness term is left out of it. Same returns as linear_step.
    double newton_step(double dt, StepStats& s, double& energy_before);
    /// Phi at the current velocities (positions x0 + dt v set): see newton_step.
    double incremental_potential(double dt, const std::vector<Eigen::Vector3d>& x0, const Eigen::VectorXd& m_v0);
    /// After a step that gained energy at the smallest substep: scales the velocities, or failing
    /// that stops the object part way along the step from `x0`, so that kinetic plus elastic
    /// energy is at most `allowed` (J); updates the energies in `s`.
    void project_energy(const std::vector<Eigen::Vector3d>& x0, double allowed, StepStats& s);
    /// A step of `dt` that must not create energy: linearised, else fully nonlinear, else halved
    /// (recursively), else with the excess energy taken out.
    void advance(double dt, int depth, StepStats& s);

    const HexModel& m_model;
    SolverOptions m_options;
    std::vector<Eigen::Vector3d> m_x, m_v, m_external;
    std::vector<unsigned char> m_fixed; ///< per dof: held by fix() or asleep
    std::vector<unsigned char> m_held;  ///< per dof: held by fix()
    std::vector<unsigned char> m_active; ///< per element: some node of it free (update_active)
    bool m_active_current = false;
    std::vector<NodeContact> m_contact;
    std::vector<Eigen::Vector3d> m_contact_x0;  ///< per contact: the node's position when it was set
    std::vector<std::int32_t> m_contact_of_node; ///< per node: index in m_contact, or -1
    double m_contact_scale = 0.0;                ///< factor of the contact stiffness in the system matrix
    PairContacts m_pairs;
    std::vector<unsigned char> m_pair_in_matrix; ///< per pair: the assembled matrix holds its stiffness
    Eigen::Vector3d m_gravity = Eigen::Vector3d::Zero();
    SystemMatrix m_matrix;
    std::vector<std::uint16_t> m_rank;          ///< per element and corner pair (c, d): d's node among c's node's neighbours
    std::vector<std::uint16_t> m_diagonal_rank; ///< per node: its own place among its neighbours
    std::vector<std::uint32_t> m_incidence_start;     ///< per node, into m_incidence
    std::vector<std::uint32_t> m_incidence;           ///< 8 element + corner, grouped by node
    std::vector<Eigen::Matrix3d> m_element_rotation;  ///< per element, world frame
    /// Runs of k_product_run consecutive elements, grouped so that no two runs of a group share a
    /// node (group_runs): the matrix-free product adds each run's element products straight into
    /// its nodes, the runs of one group in parallel.
    std::vector<std::vector<std::uint32_t>> m_run_groups;
    mutable Eigen::VectorXd m_stiffness_product; ///< sum over elements of R K R^T p, per dof (matrix-free product)
    mutable Eigen::VectorXd m_tied_p;            ///< the product's input with tied nodes filled in
    bool m_matrix_current = false;                    ///< m_matrix holds the system being solved
    Eigen::VectorXd m_diagonal;                       ///< of the system matrix (held dofs: 1)
    double m_m_scale = 0.0, m_k_scale = 0.0;          ///< system matrix = m_scale M + k_scale K
    std::vector<Eigen::Quaterniond> m_rotation;       ///< per element, index-aligned frame (warm start)
    std::vector<Eigen::Quaterniond> m_node_rotation;  ///< per node, mean of its elements'
    std::vector<double> m_element_energy;
    std::vector<VolumeHessian> m_volume_hessian; ///< per element: of its volume correction, world frame (where m_squeezed)
    std::vector<unsigned char> m_squeezed;       ///< per element: 1 where its volume correction has a Hessian
    Eigen::VectorXd m_internal;         ///< internal forces, N, per dof
    std::unique_ptr<Preconditioner> m_preconditioner;
    std::unique_ptr<NodeIntegrator> m_integrator;
    std::string m_fallback_note;
    std::vector<MaterialBehaviour> m_behaviour;
    std::vector<double> m_water;            ///< per element; empty while everything is dry
    std::vector<double> m_stiffness_scale;  ///< per element, from the water content
    std::vector<Eigen::Matrix3d> m_plastic; ///< per element; empty without plastic materials
    bool m_update_plastic = false;          ///< the next assembly starts a step: let strain creep
    double m_step_dt = 0.0;                 ///< the (sub)step being taken, s
    double m_last_dt = 0.0;                 ///< of the last dynamic solve
    bool m_element_pass_current = false;    ///< rotations and element forces match m_x
    bool m_projected_this_step = false;     ///< a substep of this frame's step lost energy it made (project_energy)
};

} // namespace vox::fem
