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
//
// Refactorisations run in the background, off the frame (one took 90-120 ms on the Is-XFEM
// bench, landing whole in single frames). When the rent-or-buy rule or the cap marks a usable
// factor stale, update() snapshots the matrix, the held dofs and the node rotations and factors
// them into a second factor on a thread of its own (at a lower priority, so that it takes the CPU
// the frame leaves), while the current factor with its patch goes on preconditioning. The new
// factor is swapped in at the first update() after the CG iterations reported since the launch
// add up to the factorisation's estimated cost in iterations (the rent-or-buy unit), waiting for
// the thread if it is not done yet. The swap point is fixed by the computation, not by the clock,
// so which factor preconditions which solve, and so every CG iterate, is the same from run to run
// whatever the threads' timing (runs are compared). Why that delay: the estimate is calibrated to
// the factorisation's time, so the thread has about the time it needs, and the stale factor's
// extra iterations meanwhile cost the frames less than the factorisation would have. While a
// factorisation runs the rule and the cap rest (one is bought already; a long solve brings the
// swap closer by its own count). Cuts made meanwhile are tracked since the snapshot, so the
// swapped-in factor is patched for them. Still taken in the frame, after waiting for any running
// factorisation (one thread at a time calls CHOLMOD and BLAS): the first factor, one replacing a
// failed factor or after invalidate(), and one for other held dofs, a shrunk system, growth
// without blocks_changed(), or a patch that failed or passed an eighth of the system. A
// background factor whose held dofs no longer fit is discarded.

#include "fem/preconditioner.hpp"

#include "fem/patch_solve.hpp"
#include "fem/supernodal_factor.hpp"

#include <future>
#include <memory>
#include <utility>

namespace vox::fem {

class RestCholesky final : public Preconditioner {
public:
    /// By default, factorisations of fewer flops than this (about 50 ms on the reference machine)
    /// are taken in the frame: below that the wait for the swap, a factorisation's worth of
    /// iterations on the stale factor, costs more than the factorisation (measured on
    /// data/scenes/cylinder_cut.json, 3.5 k dofs: CG iterations +80 % in the background).
    static constexpr double k_background_flops = 3e8;
    /// `frame`: the orthonormal index-to-world map (node rotations are in the index-aligned frame).
    /// `refactor_iterations`: a solve needing more CG iterations than this marks the factor stale
    /// whatever the running cost says. `background_flops`: refactorisations of at least this many
    /// flops run on a thread of their own (see above); infinity takes every factor in the frame.
    explicit RestCholesky(const Eigen::Matrix3d& frame, int refactor_iterations = 25, double background_flops = k_background_flops);
    ~RestCholesky() override;
    RestCholesky(const RestCholesky&) = delete;
    RestCholesky& operator=(const RestCholesky&) = delete;

    /// Also when a background factor is due to be swapped in (it may be discarded and taken again)
    /// and when changed blocks wait for their patch.
    [[nodiscard]] bool needs_matrix() const override
    {
        return m_stale || m_invalid || m_patch_dirty || (m_running.valid() && static_cast<double>(m_running_iterations) >= m_running_cost);
    }
    void update(const SystemMatrix* a, const std::vector<unsigned char>& fixed,
                const std::vector<Eigen::Quaterniond>& node_rotation) override;
    void apply(const Eigen::VectorXd& r, Eigen::VectorXd& z) const override;
    void report_iterations(int iterations) override;
    /// A running background factorisation is of the old matrix: it is discarded at the next update(),
    /// which factors in the frame.
    void invalidate() override { m_invalid = true; }
    void set_jump_blocks(std::vector<JumpBlock> jumps) override { m_jumps = std::move(jumps); }
    void blocks_changed(const std::vector<std::uint32_t>& blocks) override;
    /// Dofs of the patch solved exactly beside the factor (0 when the factor fits the system).
    [[nodiscard]] std::size_t patch_dofs() const { return m_patch.dofs(); }
    [[nodiscard]] const char* name() const override { return "warped Cholesky"; }

    /// Whether the last factorisation failed (a singular matrix: the solver falls back to Jacobi).
    [[nodiscard]] bool failed() const override { return m_failed; }
    /// Factorisations taken so far, in the frame and in the background (a discarded one included).
    [[nodiscard]] int factorizations() const { return m_factorizations; }
    /// Of those, the ones taken in the background.
    [[nodiscard]] int background_factorizations() const { return m_background_factorizations; }
    /// Updates that had to wait for a background factorisation (to swap it in, or to discard it
    /// before factoring in the frame).
    [[nodiscard]] int frames_waited() const { return m_frames_waited; }
    /// Whether a background factorisation runs or waits to be swapped in.
    [[nodiscard]] bool background_pending() const { return m_running.valid(); }
    /// The factor itself (its size, how its solves split over threads).
    [[nodiscard]] const SupernodalFactor& factor() const { return m_current->factor; }
    /// What a factorisation costs, in CG iterations (see the .cpp for the model).
    [[nodiscard]] double refactor_cost_iterations() const { return m_refactor_cost; }

private:
    /// A factor and the state it was taken at.
    struct Factorization {
        SupernodalFactor factor;
        std::vector<Eigen::Quaterniond> rotation; ///< per block, at the factorisation
        std::vector<unsigned char> fixed;
        Eigen::Index rows = 0, nonzeros = 0; ///< of the matrix: a new pattern needs a new analysis
        bool taken = false, ok = false;
        void take(const SystemMatrix& a, std::vector<unsigned char> held, std::vector<Eigen::Quaterniond> at, std::size_t solve_threads);
    };

    /// Whether update() must factor in the frame (see the header comment for when).
    [[nodiscard]] bool must_refactor(const std::vector<unsigned char>& fixed, std::size_t blocks) const;
    void refactor(const SystemMatrix& a, const std::vector<unsigned char>& fixed, const std::vector<Eigen::Quaterniond>& node_rotation);
    void launch(const SystemMatrix& a, const std::vector<unsigned char>& fixed, const std::vector<Eigen::Quaterniond>& node_rotation);
    /// Waits for the background factorisation (counting a wait that blocks) and rethrows what it threw.
    void join();
    /// Joins the background factor and makes it the current one unless its holds no longer fit.
    void swap_in(const std::vector<unsigned char>& fixed, std::size_t blocks);
    /// A new factor: no patch yet, the rent-or-buy counters reset and its cost estimated.
    void start_stretch(std::vector<unsigned char> changed, bool dirty);
    /// Builds the patch of the blocks added or changed since the factor's snapshot; false when it failed.
    bool repatch(const SystemMatrix& a, std::size_t blocks);
    void set_warps(const std::vector<Eigen::Quaterniond>& node_rotation);
    /// Whether `fixed` holds the dofs `held` holds and none beyond.
    [[nodiscard]] static bool same_holds(const std::vector<unsigned char>& held, const std::vector<unsigned char>& fixed);

    Eigen::Matrix3d m_frame;
    int m_refactor_iterations;
    double m_background_flops;
    bool m_stale = true, m_invalid = false, m_failed = false;
    int m_factorizations = 0, m_background_factorizations = 0, m_frames_waited = 0;
    double m_refactor_cost = 0.0;   ///< CG iterations
    double m_iteration_flops = 0.0; ///< of one CG iteration with the factor alone
    int m_baseline = -1;            ///< fewest iterations of a solve since the factorisation
    double m_excess = 0.0;          ///< iterations beyond the baseline since the factorisation
    std::unique_ptr<Factorization> m_current = std::make_unique<Factorization>();
    std::unique_ptr<Factorization> m_next = std::make_unique<Factorization>(); ///< the background's: only its thread touches it while it runs
    std::vector<Eigen::Matrix3d> m_warp; ///< per block: world rotation from the factored state to now
    std::vector<JumpBlock> m_jumps;
    /// The jumps the factor holds, each with sign (W_block - W_node).
    std::vector<std::pair<JumpBlock, Eigen::Matrix3d>> m_jump_warp;
    std::vector<unsigned char> m_changed; ///< per factored block: its rows changed since the factorisation
    bool m_patch_dirty = false;
    std::size_t m_covered_blocks = 0; ///< blocks the factor and its patch were built for
    PatchSolve m_patch;
    // The background factorisation into m_next: swapped in once the iterations reported since its
    // launch reach the cost; cuts since its snapshot, for its patch.
    std::future<void> m_running;
    double m_running_cost = 0.0;
    long m_running_iterations = 0;
    std::vector<unsigned char> m_changed_since_launch;
    bool m_dirty_since_launch = false;
    mutable Eigen::VectorXd m_scratch;
};

} // namespace vox::fem
