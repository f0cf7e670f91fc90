#pragma once
// The rotation of a corotational element: the orthogonal factor of the polar decomposition of the
// deformation gradient F = U S V^T -> R = U V^T (Eigen's 3 x 3 SVD). It keeps the sign of det F,
// so an element whose rest frame is a reflection (a mirroring scan transform) keeps it.

#include <Eigen/Core>
#include <Eigen/SVD>

namespace vox::fem {

/// Orthogonal factor of `f`; the identity for a degenerate (non-finite) gradient.
[[nodiscard]] inline Eigen::Matrix3d polar_rotation(const Eigen::Matrix3d& f)
{
    if (!f.allFinite()) return Eigen::Matrix3d::Identity();
    const Eigen::JacobiSVD<Eigen::Matrix3d> svd(f, Eigen::ComputeFullU | Eigen::ComputeFullV);
    return svd.matrixU() * svd.matrixV().transpose();
}

} // namespace vox::fem
