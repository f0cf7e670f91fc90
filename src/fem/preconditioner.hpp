#pragma once
// What the conjugate-gradient solve of the implicit solver asks of a preconditioner: a set-up for
// each new system matrix, then z = P r for residuals r. Held degrees of freedom have identity rows
// and columns in the matrix and zero residuals; P must keep them zero.

#include "fem/factor_failure.hpp"

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <Eigen/Sparse>

#include <cstdint>
#include <vector>

namespace vox::fem {

using SystemMatrix = Eigen::SparseMatrix<double, Eigen::RowMajor>;

/// A dof block that holds the jump between two fields turning apart: the enriched dofs a of a
/// node cut by a crack (fields x - H a and x + (1 - H) a on the node's two sides, H its side).
/// When the sides turn by R_0 and R_1 the jump turns as a -> (R_1 - R_0) x + R_other a, which a
/// warping preconditioner can follow instead of turning a like an ordinary block.
struct JumpBlock {
    std::uint32_t block = 0; ///< the jump's dof block; its rotation is the other side's
    std::uint32_t node = 0;  ///< the node's own dof block; its rotation is the node's side's
    double sign = 1.0;       ///< +1 when the node is on side 0 (R_1 - R_0 = R_block - R_node), else -1
};

class Preconditioner {
public:
    virtual ~Preconditioner() = default;
    /// Whether the next update() reads the system matrix. When it does not, the solver skips
    /// assembling the matrix and multiplies element by element.
    [[nodiscard]] virtual bool needs_matrix() const { return true; }
    /// A new system: the matrix `a` (null when needs_matrix() said it was not needed; `fixed` flags
    /// held dofs). `node_rotation` is each node's current rotation (the mean of its elements',
    /// index-aligned frame) for preconditioners built at another state.
    virtual void update(const SystemMatrix* a, const std::vector<unsigned char>& fixed,
                        const std::vector<Eigen::Quaterniond>& node_rotation) = 0;
    virtual void apply(const Eigen::VectorXd& r, Eigen::VectorXd& z) const = 0;
    /// Told how many iterations the last solve took, so a preconditioner built at another state can
    /// decide to rebuild.
    virtual void report_iterations(int /*iterations*/) {}
    /// The matrix has changed beyond what update() tracks (a new time step, newly held dofs):
    /// rebuild next time.
    virtual void invalidate() {}
    /// The system grew or the rows of these dof blocks changed beyond what update() tracks (a crack
    /// grew into their elements) while the rest stayed as it was. By default: rebuild.
    virtual void blocks_changed(const std::vector<std::uint32_t>& /*blocks*/) { invalidate(); }
    /// The jump blocks of the system (see JumpBlock); ignored unless the preconditioner warps.
    virtual void set_jump_blocks(std::vector<JumpBlock> /*jumps*/) {}
    /// The dof blocks whose rows carry contact terms in the next update()'s matrix (a tool's
    /// penalty, pieces pressed together): terms that move on with the tool from step to step, so
    /// a preconditioner kept across steps knows which rows it took them in.
    virtual void set_contact_blocks(std::vector<std::uint32_t> /*blocks*/) {}
    [[nodiscard]] virtual const char* name() const = 0;
    /// True when the last update could not build the preconditioner (a singular matrix).
    [[nodiscard]] virtual bool failed() const { return false; }
    /// Why it failed: the matrix was not positive definite, or nearly singular; the dof where the
    /// failure showed (-1: not known). The solver names the node and the likely cause.
    [[nodiscard]] virtual FactorFailure failure() const { return {}; }
};

} // namespace vox::fem
