#pragma once
// Preconditioned conjugate gradients as the simulation solvers use them (the branched grid's and
// Is-XFEM's): warm started from x, stopping when the Jacobi-scaled residual D^-1/2 r falls below
// the tolerance relative to the scaled right-hand side. Unscaled, nodes that carry almost no
// material (an element holding one voxel of 512) would barely count in the residual and could
// move wildly while the solve "converges".

#include <Eigen/Core>

namespace vox::fem {

struct CgResult {
    int iterations = 0;
    double residual = 0.0; ///< relative, scaled
};

/// Solves A x = rhs from the x given. `multiply(p, out)`: out = A p; `precondition(r, z)`: z = P r;
/// `inv_sqrt_diagonal`: D^-1/2. Stops at the tolerance, after `max_iterations`, or when A or P is
/// no longer positive along the search (not positive definite, or r = 0: nothing more to gain).
template <class Multiply, class Precondition>
CgResult conjugate_gradient(Multiply&& multiply, Precondition&& precondition, const Eigen::VectorXd& rhs,
                            const Eigen::VectorXd& inv_sqrt_diagonal, double tolerance, int max_iterations, Eigen::VectorXd& x)
{
    CgResult result;
    const double b_norm = rhs.cwiseProduct(inv_sqrt_diagonal).norm();
    if (b_norm == 0.0) {
        x.setZero();
        return result;
    }
    auto scaled_norm = [&](const Eigen::VectorXd& res) { return res.cwiseProduct(inv_sqrt_diagonal).norm() / b_norm; };
    const Eigen::Index n = rhs.size();
    Eigen::VectorXd r(n), z(n), q(n);
    multiply(x, q);
    r = rhs - q;
    precondition(r, z);
    Eigen::VectorXd p = z;
    double rz = r.dot(z);
    result.residual = scaled_norm(r);
    while (result.residual > tolerance && result.iterations < max_iterations) {
        multiply(p, q);
        const double pq = p.dot(q);
        if (!(pq > 0.0)) break; // not positive definite along p: stop rather than diverge
        const double alpha = rz / pq;
        x += alpha * p;
        r -= alpha * q;
        precondition(r, z);
        const double rz_next = r.dot(z);
        result.residual = scaled_norm(r);
        ++result.iterations;
        if (!(rz_next > 0.0)) break; // a semidefinite preconditioner (or r = 0)
        p = z + (rz_next / rz) * p;
        rz = rz_next;
    }
    return result;
}

} // namespace vox::fem
