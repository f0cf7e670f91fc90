#pragma once
// The warped-stiffness preconditioner: a sparse Cholesky factor of the system matrix (supernodal,
// applied in single precision: fem/supernodal_factor.hpp) taken once and again whenever it has
// gone stale, applied to the current residual in each node's rotated frame: P = W A_0^-1 W^T, W the
// block-diagonal rotation of every node from the factored state to the current one. A corotational
// matrix differs from the factored one mostly by those rotations, so CG converges in a few
// iterations without a factorisation per step (the idea of Hecht, Lee, Shewchuk and O'Brien 2012,
// without their partial updates: the factor is taken whole).
//
// When to refactor is a rent-or-buy decision: each solve costs the iterations the factor needed
// right after it was taken plus an excess that grows as the object turns away from the factored
// state. The excess iterations are summed, and once they cost as much as a new factorisation
// would (an estimate from the flop counts), the factor is taken again: the classic ski-rental
// rule, which for one stretch between factorisations spends at most twice what the best choice in
// hindsight would. A hard cap on the iterations of one solve refactors at once.
//
// Cut (XFEM) systems: jump blocks (preconditioner.hpp) are warped with the two sides of their
// crack, W = [R_node 0; sign (R_block - R_node) R_block] on (node, jump), so two pieces turning
// apart keep the factor fresh. A cut that adds dofs and changes the rows of a few old ones
// (blocks_changed) keeps the factor, extended by zero over the new dofs, and adds an exact solve
// on the patch of new and changed blocks with one ring of neighbours (additive Schwarz,
// fem/patch_solve.hpp), until the rent-or-buy rule says a new factor pays (the patch's solves count
// as extra iterations) or the patch grows past an eighth of the system. (The factor with only
// block Jacobi on the new dofs stalls CG: the new enriched dofs couple strongly to their nodes'
// own; measured on the cut bar of data/scenes/bar_cut_isxfem.json: no convergence in 2,000
// iterations.)

#include "fem/preconditioner.hpp"

#include "fem/patch_solve.hpp"
#include "fem/supernodal_factor.hpp"

#include <utility>

namespace vox::fem {

class RestCholesky final : public Preconditioner {
public:
    /// `frame`: the orthonormal index-to-world map (node rotations are in the index-aligned frame).
    /// `refactor_iterations`: a solve needing more CG iterations than this marks the factor stale
    /// whatever the running cost says.
    explicit RestCholesky(const Eigen::Matrix3d& frame, int refactor_iterations = 25);

    [[nodiscard]] bool needs_matrix() const override { return m_stale; }
    void update(const SystemMatrix* a, const std::vector<unsigned char>& fixed,
                const std::vector<Eigen::Quaterniond>& node_rotation) override;
    void apply(const Eigen::VectorXd& r, Eigen::VectorXd& z) const override;
    void report_iterations(int iterations) override;
    void invalidate() override { m_stale = true; }
    void set_jump_blocks(std::vector<JumpBlock> jumps) override { m_jumps = std::move(jumps); }
    void blocks_changed(const std::vector<std::uint32_t>& blocks) override;
    /// Dofs of the patch solved exactly beside the factor (0 when the factor fits the system).
    [[nodiscard]] std::size_t patch_dofs() const { return m_patch.dofs(); }
    [[nodiscard]] const char* name() const override { return "warped Cholesky"; }

    /// Whether the last factorisation failed (a singular matrix: the solver falls back to Jacobi).
    [[nodiscard]] bool failed() const override { return m_failed; }
    /// Factorisations taken so far.
    [[nodiscard]] int factorizations() const { return m_factorizations; }
    /// The factor itself (its size, how its solves split over threads).
    [[nodiscard]] const SupernodalFactor& factor() const { return m_factor; }
    /// What a factorisation costs, in CG iterations (see the .cpp for the model).
    [[nodiscard]] double refactor_cost_iterations() const { return m_refactor_cost; }

private:
    void refactor(const SystemMatrix& a, const std::vector<unsigned char>& fixed, const std::vector<Eigen::Quaterniond>& node_rotation);
    /// Whether `fixed` holds the factored dofs as factored and none added since.
    [[nodiscard]] bool same_holds(const std::vector<unsigned char>& fixed) const;

    Eigen::Matrix3d m_frame;
    int m_refactor_iterations;
    bool m_stale = true, m_failed = false;
    int m_factorizations = 0;
    double m_refactor_cost = 0.0; ///< CG iterations
    double m_iteration_flops = 0.0; ///< of one CG iteration with the factor alone
    int m_baseline = -1;          ///< fewest iterations of a solve since the factorisation
    double m_excess = 0.0;        ///< iterations beyond the baseline since the factorisation
    SupernodalFactor m_factor;
    std::vector<Eigen::Quaterniond> m_factored_rotation;
    std::vector<Eigen::Matrix3d> m_warp; ///< per block: world rotation from the factored state to now
    std::vector<JumpBlock> m_jumps;
    /// The jumps the factor holds, each with sign (W_block - W_node).
    std::vector<std::pair<JumpBlock, Eigen::Matrix3d>> m_jump_warp;
    std::vector<unsigned char> m_changed;     ///< per factored block: its rows changed since the factorisation
    bool m_patch_dirty = false;
    std::size_t m_covered_blocks = 0; ///< blocks the factor and its patch were built for
    PatchSolve m_patch;
    std::vector<unsigned char> m_fixed;
    Eigen::Index m_rows = 0, m_nonzeros = 0; ///< of the matrix last analysed: a new pattern needs a new analysis
    mutable Eigen::VectorXd m_scratch;
};

} // namespace vox::fem
