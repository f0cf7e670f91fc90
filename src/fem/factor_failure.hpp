#pragma once
// Why a Cholesky factorisation of a system matrix failed, and where: what the solver tells the
// user when it falls back to another preconditioner.

#include <Eigen/Core>

#include <string>

namespace vox::fem {

struct FactorFailure {
    bool failed = false;
    /// True when the matrix is indefinite: a pivot came out negative or zero and stays so with
    /// the diagonal raised by 1e-8 of its largest entry. False when it is singular or nearly so
    /// (positive semi-definite: a piece nothing holds, with no mass to hold it).
    bool not_positive_definite = false;
    int dof = -1;              ///< the matrix's row (dof) whose pivot failed or was the smallest
    double pivot_ratio = 0.0;  ///< the smallest pivot over the largest when all were positive; 0: singular
};

/// The note a solver gives when its preconditioner `name` failed as `f` and Jacobi took over:
/// what failed and at which node (`where_m`, metres; null when not known), with the likely cause
/// only where the system says it: a nearly singular system without mass (`quasi_static`) is a
/// piece nothing holds, all of it when nothing is held (`anything_held`).
[[nodiscard]] std::string fallback_note(const char* name, const FactorFailure& f, const Eigen::Vector3d* where_m, bool quasi_static,
                                        bool anything_held);

} // namespace vox::fem
