#pragma once
// The rotation of a corotational element: the rotation R that maximises tr(R^T A), found by the
// iteration of Müller, Bender, Chentanez and Macklin 2016 ("A Robust Method to Extract the
// Rotational Part of Deformations") with Newton steps, warm-started from the previous step's
// rotation. For det A > 0
// it is the orthogonal factor of the polar decomposition; unlike the SVD factor it stays a proper
// rotation when an element is inverted (det A <= 0), so the elastic force pushes the element back
// out instead of treating the inverted state as a mirrored rest state. Warm-started it needs two
// or three iterations a step, several times cheaper than a 3 x 3 SVD.

#include <Eigen/Cholesky>
#include <Eigen/Core>
#include <Eigen/Geometry>

#include <cmath>

namespace vox::fem {

/// Updates `q` to the rotation nearest `a`; keeps `q` when `a` is not finite.
///
/// Each iteration turns R by the world-frame rotation vector omega that maximises tr(R^T A) to
/// second order: the gradient is the torque sum_i r_i x a_i and the Hessian is tr(B) I - sym(B),
/// B = A R^T, so omega = (tr(B) I - sym(B))^-1 torque, a Newton step that converges
/// quadratically. Müller et al. replace the Hessian by tr(B) I, which converges only linearly
/// (about a third of the error a step near a rigid state: 20 iterations to 1e-12 from a step's
/// worth of turning); their step is kept where the Hessian is not positive definite (far from
/// the answer, an inverted element), since it always goes uphill. The turn is applied as the
/// quaternion (1, omega / 2) normalised, a rotation by 2 atan(|omega| / 2): off by |omega|^3 / 12,
/// which the next iteration takes up, and no sine or cosine. A Newton step under 1e-6 rad leaves an
/// error of its square, 1e-12 rad, so the iteration stops there; Müller's steps go on to 1e-12.
inline void extract_rotation(const Eigen::Matrix3d& a, Eigen::Quaterniond& q, int max_iterations = 30)
{
    if (!a.allFinite()) return;
    for (int it = 0; it < max_iterations; ++it) {
        const Eigen::Matrix3d r = q.toRotationMatrix();
        const Eigen::Vector3d torque = r.col(0).cross(a.col(0)) + r.col(1).cross(a.col(1)) + r.col(2).cross(a.col(2));
        const Eigen::Matrix3d b = a * r.transpose();
        const double alignment = b.trace();
        Eigen::Matrix3d hessian = -0.5 * (b + b.transpose());
        hessian.diagonal().array() += alignment;
        const Eigen::LLT<Eigen::Matrix3d> newton(hessian);
        // Newton only where the Hessian is safely positive definite (a pivot far from round-off).
        const bool use_newton = newton.info() == Eigen::Success &&
                                newton.matrixLLT().diagonal().minCoeff() > 1e-4 * std::sqrt(std::abs(alignment) + 1e-300);
        const Eigen::Vector3d omega = use_newton ? Eigen::Vector3d(newton.solve(torque)) : Eigen::Vector3d(torque / (std::abs(alignment) + 1e-9));
        const double angle = omega.norm();
        if (!(angle >= 1e-12)) break;
        q = Eigen::Quaterniond(1.0, 0.5 * omega.x(), 0.5 * omega.y(), 0.5 * omega.z()) * q;
        q.normalize();
        if (use_newton && angle < 1e-6) break; // quadratic: the error left is about angle^2
    }
}

/// Adds rotation q to a running sum of quaternions with the sign nearer the sum (q and -q are the
/// same rotation); the normalised sum is the mean rotation.
inline void accumulate_rotation(Eigen::Vector4d& sum, const Eigen::Quaterniond& q)
{
    const Eigen::Vector4d c = q.coeffs();
    sum += sum.dot(c) < 0.0 ? -c : c;
}

} // namespace vox::fem
