#pragma once
// The warped-stiffness preconditioner: a sparse Cholesky factor of the system matrix (supernodal,
// applied in single precision: fem/supernodal_factor.hpp) taken once and again whenever it has
// gone stale, applied to the current residual in each node's rotated frame: P = W A_0^-1 W^T, W the
// block-diagonal rotation of every node from the factored state to the current one. A corotational
// matrix differs from the factored one mostly by those rotations, so CG converges in a few
// iterations without a factorisation per step (the idea of Hecht, Lee, Shewchuk and O'Brien 2012;
// where they refactor the changed part, a cut here is corrected for by a low-rank update, below).
//
// When to refactor is a rent-or-buy decision: each solve costs the iterations the factor needed
// right after it was taken plus an excess that grows as the object turns away from the factored
// state. The excess iterations are summed, and once they cost as much as a new factorisation
// would (an estimate from the flop counts), the factor is taken again: the classic ski-rental
// rule, which for one stretch between factorisations spends at most twice what the best choice in
// hindsight would. A hard cap on the iterations of one solve refactors at once.
//
// Cut systems: jump blocks (preconditioner.hpp) are warped with the two sides of their crack,
// W = [R_node 0; sign (R_block - R_node) R_block] on (node, jump), so two pieces turning apart keep
// the factor fresh. A cut that adds dofs and changes the rows of a few old ones (blocks_changed)
// keeps the factor, extended by the identity over the new dofs, corrected exactly for the change
// over those rows by the Woodbury identity (fem/factor_correction.hpp): the factor preconditions
// the cut system as a new factor of it would, until the rent-or-buy rule says a new factor pays
// (the correction's build and its extra work in each application count as extra iterations) or
// the corrected rows pass an eighth of the system. A correction whose build would cost more than
// a factorisation (a cut through many elements at once) is not built: an exact solve on the patch
// of changed blocks with one ring is added to the factor instead (additive Schwarz,
// fem/patch_solve.hpp: sound, not exact) until a new factor comes, as it is for systems whose cuts
// change more rows than they name (set_exact_cuts). The rows whose contact terms moved are
// corrected with them (set_contact_blocks: those of the factor's snapshot and this step's; the tool
// presses where it cuts). Measured on the liver incision (docs/benchmarks/cutting.md): CG takes
// 3 - 5 iterations while cutting, where an exact solve on the patch of changed blocks added to the
// factor (additive Schwarz, before) needed 15 at the median, the factor still joining the
// material across the faces the stroke had opened.
//
// Refactorisations run in the background, off the frame (one took 90-120 ms on the Is-XFEM
// bench, landing whole in single frames), when the process has a second core to run them on.
// Confined to one core, the thread would take the frames' core in slices of a few milliseconds
// over a dozen frames, so the factor is taken in the frame instead, and bought at twice the price
// (the frame it lands in stalls). When the rent-or-buy rule or the cap marks a usable
// factor stale, update() snapshots the matrix, the held dofs and the node rotations and factors
// them into a second factor on a thread of its own (at a lower priority, so that it takes the CPU
// the frame leaves), while the current factor with its correction goes on preconditioning. The new
// factor is swapped in at the first update() after the CG iterations reported since the launch
// add up to the factorisation's estimated cost in iterations (the rent-or-buy unit), waiting for
// the thread if it is not done yet. The swap point is fixed by the computation, not by the clock,
// so which factor preconditions which solve, and so every CG iterate, is the same from run to run
// whatever the threads' timing (runs are compared). Why that delay: the estimate is calibrated to
// the factorisation's time, so the thread has about the time it needs, and the stale factor's
// extra iterations meanwhile cost the frames less than the factorisation would have. While a
// factorisation runs the rule and the cap rest (one is bought already; a long solve brings the
// swap closer by its own count). Cuts made meanwhile are tracked since the snapshot, so the
// swapped-in factor is corrected for them. Still taken in the frame, after waiting for any running
// factorisation (one thread at a time calls CHOLMOD and BLAS): the first factor, one replacing a
// failed factor or after invalidate(), and one for other held dofs, a shrunk system, growth
// without blocks_changed(), or a correction that failed or passed an eighth of the system. A
// background factor whose held dofs no longer fit is discarded.

#include "fem/preconditioner.hpp"

#include "fem/factor_correction.hpp"
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
    /// k_background_flops, or infinity for a process allowed on one core only: there the
    /// background thread would take the frames' own core in slices of a few milliseconds, landing
    /// in a dozen frames instead of one.
    [[nodiscard]] static double background_flops_here();
    /// Whether a cut is corrected for exactly (the default), or only by the patch solve: for a
    /// system whose cuts change rows beyond those blocks_changed() names (Is-XFEM: a cut's
    /// enriched blocks change the rows of everything they couple to), where an exact correction
    /// over the named rows alone would not be positive definite.
    void set_exact_cuts(bool exact) { m_exact_cuts = exact; }
    ~RestCholesky() override;
    RestCholesky(const RestCholesky&) = delete;
    RestCholesky& operator=(const RestCholesky&) = delete;

    /// Also when a background factor is due to be swapped in (it may be discarded and taken again)
    /// and when changed blocks wait for their correction.
    [[nodiscard]] bool needs_matrix() const override
    {
        return m_stale || m_invalid || m_correction_dirty || (m_running.valid() && static_cast<double>(m_running_iterations) >= m_running_cost);
    }
    void update(const SystemMatrix* a, const std::vector<unsigned char>& fixed,
                const std::vector<Eigen::Quaterniond>& node_rotation) override;
    void apply(const Eigen::VectorXd& r, Eigen::VectorXd& z) const override;
    void report_iterations(int iterations) override;
    /// A running background factorisation is of the old matrix: it is discarded at the next update(),
    /// which factors in the frame.
    void invalidate() override { m_invalid = true; }
    void set_jump_blocks(std::vector<JumpBlock> jumps) override { m_jumps = std::move(jumps); }
    void set_contact_blocks(std::vector<std::uint32_t> blocks) override { m_contact_blocks = std::move(blocks); }
    void blocks_changed(const std::vector<std::uint32_t>& blocks) override;
    /// Dofs whose rows the factor is corrected for (0 when the factor fits the system).
    [[nodiscard]] std::size_t correction_dofs() const { return m_correction.dofs(); }
    /// Dofs of the patch solved beside the factor instead, when the correction cost too much.
    [[nodiscard]] std::size_t patch_dofs() const { return m_patch.dofs(); }
    [[nodiscard]] const char* name() const override { return "warped Cholesky"; }

    /// Whether the last factorisation failed (a singular matrix: the solver falls back to Jacobi).
    [[nodiscard]] bool failed() const override { return m_failed; }
    [[nodiscard]] FactorFailure failure() const override { return m_failed ? m_current->factor.failure() : FactorFailure{}; }
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
        SystemMatrix matrix; ///< what was factored (the correction's reference)
        std::vector<std::uint32_t> contact_blocks; ///< rows that held contact terms then
        Eigen::Index rows = 0, nonzeros = 0; ///< of the matrix: a new pattern needs a new analysis
        bool taken = false, ok = false;
        void take(const SystemMatrix& a, std::vector<unsigned char> held, std::vector<Eigen::Quaterniond> at, std::vector<std::uint32_t> contacts,
                  std::size_t solve_threads);
    };

    /// Whether update() must factor in the frame (see the header comment for when).
    [[nodiscard]] bool must_refactor(const std::vector<unsigned char>& fixed, std::size_t blocks) const;
    void refactor(const SystemMatrix& a, const std::vector<unsigned char>& fixed, const std::vector<Eigen::Quaterniond>& node_rotation);
    void launch(const SystemMatrix& a, const std::vector<unsigned char>& fixed, const std::vector<Eigen::Quaterniond>& node_rotation);
    /// Waits for the background factorisation (counting a wait that blocks) and rethrows what it threw.
    void join();
    /// Joins the background factor and makes it the current one unless its holds no longer fit.
    void swap_in(const std::vector<unsigned char>& fixed, std::size_t blocks);
    /// A new factor: no correction yet, the rent-or-buy counters reset and its cost estimated.
    void start_stretch(std::vector<unsigned char> changed, bool dirty);
    /// Corrects the factor for the blocks added or changed since its snapshot; false when that failed.
    bool recorrect(const SystemMatrix& a, const std::vector<unsigned char>& fixed, std::size_t blocks);
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
    std::vector<std::uint32_t> m_contact_blocks; ///< this step's
    /// The jumps the factor holds, each with sign (W_block - W_node).
    std::vector<std::pair<JumpBlock, Eigen::Matrix3d>> m_jump_warp;
    std::vector<unsigned char> m_changed; ///< per factored block: its rows changed since the factorisation
    bool m_correction_dirty = false;
    std::size_t m_covered_blocks = 0; ///< blocks the factor and its correction were built for
    FactorCorrection m_correction;
    PatchSolve m_patch; ///< when the correction would cost more than it is worth, or is not asked for
    bool m_exact_cuts = true;
    // The background factorisation into m_next: swapped in once the iterations reported since its
    // launch reach the cost; cuts since its snapshot, for its correction.
    std::future<void> m_running;
    double m_running_cost = 0.0;
    long m_running_iterations = 0;
    std::vector<unsigned char> m_changed_since_launch;
    bool m_dirty_since_launch = false;
    mutable Eigen::VectorXd m_scratch, m_new_z;
};

} // namespace vox::fem
