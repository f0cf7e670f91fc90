#pragma once
// The rotation of a corotational element: the rotation R that maximises tr(R^T A), found by the
// iteration of Müller, Bender, Chentanez and Macklin 2016 ("A Robust Method to Extract the
// Rotational Part of Deformations"), warm-started from the previous step's rotation. For det A > 0
// it is the orthogonal factor of the polar decomposition; unlike the SVD factor it stays a proper
// rotation when an element is inverted (det A <= 0), so the elastic force pushes the element back
// out instead of treating the inverted state as a mirrored rest state. Warm-started it needs one
// or two iterations a step, several times cheaper than a 3 x 3 SVD.

#include <Eigen/Core>
#include <Eigen/Geometry>

#include <cmath>

namespace vox::fem {

/// Updates `q` to the rotation nearest `a`; keeps `q` when `a` is not finite.
inline void extract_rotation(const Eigen::Matrix3d& a, Eigen::Quaterniond& q, int max_iterations = 30)
{
    if (!a.allFinite()) return;
    for (int it = 0; it < max_iterations; ++it) {
        const Eigen::Matrix3d r = q.toRotationMatrix();
        const Eigen::Vector3d torque = r.col(0).cross(a.col(0)) + r.col(1).cross(a.col(1)) + r.col(2).cross(a.col(2));
        const double alignment = std::abs(r.col(0).dot(a.col(0)) + r.col(1).dot(a.col(1)) + r.col(2).dot(a.col(2)));
        const Eigen::Vector3d omega = torque / (alignment + 1e-9);
        const double angle = omega.norm();
        if (angle < 1e-12) break;
        q = Eigen::Quaterniond(Eigen::AngleAxisd(angle, omega / angle)) * q;
        q.normalize();
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
