#pragma once
// What the conjugate-gradient solve of the implicit solver asks of a preconditioner: a set-up for
// each new system matrix, then z = P r for residuals r. Held degrees of freedom have identity rows
// and columns in the matrix and zero residuals; P must keep them zero.

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <Eigen/Sparse>

#include <vector>

namespace vox::fem {

using SystemMatrix = Eigen::SparseMatrix<double, Eigen::RowMajor>;

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
    [[nodiscard]] virtual const char* name() const = 0;
    /// True when the last update could not build the preconditioner (a singular matrix).
    [[nodiscard]] virtual bool failed() const { return false; }
};

} // namespace vox::fem
