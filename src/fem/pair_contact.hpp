#pragma once
// Contact between two material points of one model that the elements do not join: a piece lying
// on another, the two walls of a cut pressed together. Unlike a tool's contact (NodeContact,
// lumped on one side's nodes against a world that does not give), its stiffness couples the two
// sides: it resists their relative motion along the contact's normal, not their common motion.
// Lumped on each side alone it would also resist the pair's motion through space, and two pieces
// falling together, touching, would be held back as if glued to the air.
//
// Each point moves as a weighted sum of the model's dof blocks (a branched-grid element's
// trilinear weights on its nodes; an Is-XFEM tetrahedron's standard and enriched blocks); one
// list holds both points, the second's weights negated, so that
//     g(x) = normal . sum_i w_i x_i
// is the first point's height over the second along the normal. The pair is pushed apart by
//     f(x) = force_n - stiffness_n_per_m (g(x) - g_set),
// the first point along +normal, the second along -normal (block i gets w_i f normal): a
// linearised penalty, taken implicitly with the rank-one stiffness k c c^T, c_i = w_i normal.

#include "fem/preconditioner.hpp"

#include <Eigen/Core>

#include <cstdint>
#include <vector>

namespace vox::fem {

struct BlockWeight {
    std::uint32_t block = 0;
    double weight = 0.0;
};

struct PairContact {
    std::vector<BlockWeight> terms;                       ///< each block once
    Eigen::Vector3d normal = Eigen::Vector3d::UnitZ();    ///< unit, world
    double force_n = 0.0;                                 ///< at the positions it was set at
    double stiffness_n_per_m = 0.0;                       ///< d force / d gap, >= 0
    /// Apart at the step's start (a point arriving, or resting within reach of gravity's
    /// look-ahead): it waits out of the solve until a solve ends with it pressed in.
    bool waiting = false;
};

/// How many times a step settles which contacts act and solves again: it lets go of those that
/// pull at its end and lets in the waiting ones pressed in at its end. Once is not enough where
/// many contacts touch: a piece resting on a table with 1,500 contacts within microns kept 478 of
/// them pulling after one pass, holding it down with 1.6 N (13 times its weight). A contact let
/// go stays out for the step and one let in can only be let go, so the passes end; one let go too
/// early is in at the next step's start and pushes then.
inline constexpr int k_release_passes = 8;

struct PairForceSum {
    double magnitude_n = 0.0;
    Eigen::Vector3d vector_n = Eigen::Vector3d::Zero();
};

/// Adds `weight` on `block` to `terms`, merging it with the block's term when it has one (a point
/// and the face it presses may share blocks).
void add_term(std::vector<BlockWeight>& terms, std::uint32_t block, double weight);

/// Adds `scale` times p's stiffness k c c^T to `matrix` (3 x 3 blocks by dof block, each row's
/// columns sorted) when the matrix's pattern joins every two of p's blocks (one side, or two
/// sides in one element; not two pieces), leaving the dofs `fixed` alone (their rows and columns
/// stay as they are). Returns whether it did. A solver does this so that the contact's stiffness
/// reaches a preconditioner factored from the matrix: without it each contact costs CG about an
/// iteration (a piece resting on a table: 2 iterations a step became 380).
bool add_to_matrix(const PairContact& p, double scale, const std::vector<unsigned char>& fixed, SystemMatrix& matrix);

/// The pair contacts a solver takes for its next steps, with the gaps they were set at.
class PairContacts {
public:
    /// Replaces the contacts; `x` the block positions they were measured at. Throws
    /// std::invalid_argument for a block out of range or a negative stiffness.
    void set(std::vector<PairContact> pairs, const std::vector<Eigen::Vector3d>& x);
    [[nodiscard]] bool empty() const { return m_pairs.empty(); }
    [[nodiscard]] const std::vector<PairContact>& pairs() const { return m_pairs; }

    /// f += the contacts' forces at positions x (per dof, 3 per block).
    void add_forces(const std::vector<Eigen::Vector3d>& x, Eigen::VectorXd& f) const;
    /// out += scale K p on the dofs not `fixed` (K the stiffness, p per dof, fixed per dof),
    /// leaving out the contacts `skip` flags (those a matrix holds already), when given.
    void add_product(const Eigen::VectorXd& p, double scale, const std::vector<unsigned char>& fixed, Eigen::VectorXd& out,
                     const std::vector<unsigned char>* skip = nullptr) const;
    /// d += scale diag(K), leaving out the contacts `skip` flags, when given.
    void add_diagonal(double scale, Eigen::VectorXd& d, const std::vector<unsigned char>* skip = nullptr) const;
    /// The contacts' potential at x relative to where they were set: -f (g - g_set) + k (g - g_set)^2 / 2.
    [[nodiscard]] double potential(const std::vector<Eigen::Vector3d>& x) const;
    /// The sum of contacts first..last-1's forces at positions x (those that would pull count 0):
    /// their magnitudes, N, and as a vector on the first points (along +normal), N.
    [[nodiscard]] PairForceSum force_sum(const std::vector<Eigen::Vector3d>& x, std::size_t first, std::size_t last) const;
    /// The contacts still held that would pull at positions x (f(x) < 0: the two sides part
    /// farther than the penalty's linear model allows).
    [[nodiscard]] std::vector<std::size_t> pulling(const std::vector<Eigen::Vector3d>& x) const;
    /// The block positions at the end of a step of `dt` from x at velocities `v` (3 per block).
    [[nodiscard]] static std::vector<Eigen::Vector3d> step_end(const std::vector<Eigen::Vector3d>& x, double dt, const Eigen::VectorXd& v);
    /// Lets go of contacts `which`: a contact only ever pushes.
    void release(const std::vector<std::size_t>& which);
    /// The waiting contacts that would be pressed in at positions x: they are to join the solve.
    [[nodiscard]] std::vector<std::size_t> arriving(const std::vector<Eigen::Vector3d>& x) const;
    /// Lets contacts `which` (waiting) join the solve.
    void activate(const std::vector<std::size_t>& which);
    /// Lets go of the contacts that would pull at positions x and lets in the waiting ones pressed
    /// in there. Returns how many changed.
    std::size_t settle(const std::vector<Eigen::Vector3d>& x);
    /// v^T K v (per block velocities): what a step's linearised contact loses to the work check.
    [[nodiscard]] double stiffness_product(const std::vector<Eigen::Vector3d>& v) const;

private:
    [[nodiscard]] double gap(const PairContact& p, const std::vector<Eigen::Vector3d>& x) const;
    /// Contact i's force at positions x (negative: it would pull).
    [[nodiscard]] double force_at(std::size_t i, const std::vector<Eigen::Vector3d>& x) const
    {
        return m_pairs[i].force_n - m_pairs[i].stiffness_n_per_m * (gap(m_pairs[i], x) - m_gap_set[i]);
    }
    std::vector<PairContact> m_pairs;
    std::vector<double> m_gap_set;
    /// A waiting contact's force and stiffness, held back (its pair's are 0 until it joins).
    std::vector<std::pair<double, double>> m_waiting;
};

} // namespace vox::fem
