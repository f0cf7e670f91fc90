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
};

/// Adds `weight` on `block` to `terms`, merging it with the block's term when it has one (a point
/// and the face it presses may share blocks).
void add_term(std::vector<BlockWeight>& terms, std::uint32_t block, double weight);

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
    /// out += scale K p on the dofs not `fixed` (K the stiffness, p per dof, fixed per dof).
    void add_product(const Eigen::VectorXd& p, double scale, const std::vector<unsigned char>& fixed, Eigen::VectorXd& out) const;
    /// d += scale diag(K).
    void add_diagonal(double scale, Eigen::VectorXd& d) const;
    /// The contacts' potential at x relative to where they were set: -f (g - g_set) + k (g - g_set)^2 / 2.
    [[nodiscard]] double potential(const std::vector<Eigen::Vector3d>& x) const;
    /// The sum of the contacts' force magnitudes at positions x (those that would pull count 0), N.
    [[nodiscard]] double total_force(const std::vector<Eigen::Vector3d>& x) const;
    /// Lets go of the contacts that would pull at positions x (f(x) < 0: the two sides part
    /// farther than the penalty's linear model allows): a contact only ever pushes. Returns how many.
    std::size_t release_pulling(const std::vector<Eigen::Vector3d>& x);
    /// The same at the end of a step of `dt` from x at velocities `v` (3 per block).
    std::size_t release_pulling(const std::vector<Eigen::Vector3d>& x, double dt, const Eigen::VectorXd& v);
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
};

} // namespace vox::fem
