#pragma once
// The von Mises stress of an element written for ParaView, the same for both methods: the
// corotational small strain of a deformation gradient (its polar decomposition's stretch less
// the identity), less the plastic strain, through Hooke's law.

#include "grid/hex8.hpp"

#include <Eigen/SVD>

#include <cmath>

namespace vox::sim {

/// `f`: the deformation gradient; `scale`: the stiffness scale (the wet law), 1 dry.
[[nodiscard]] inline double von_mises_pa(const Eigen::Matrix3d& f, const grid::Lame& lame,
                                         const Eigen::Matrix3d& plastic_strain = Eigen::Matrix3d::Zero(), double scale = 1.0)
{
    const Eigen::JacobiSVD<Eigen::Matrix3d> svd(f, Eigen::ComputeFullU | Eigen::ComputeFullV);
    Eigen::Matrix3d u = svd.matrixU();
    const Eigen::Matrix3d w = svd.matrixV();
    if ((u * w.transpose()).determinant() < 0.0) u.col(2) *= -1.0; // a proper rotation
    const Eigen::Matrix3d stretch = (u * w.transpose()).transpose() * f;
    const Eigen::Matrix3d strain = 0.5 * (stretch + stretch.transpose()) - Eigen::Matrix3d::Identity() - plastic_strain;
    const Eigen::Matrix3d stress = scale * (lame.lambda * strain.trace() * Eigen::Matrix3d::Identity() + 2.0 * lame.mu * strain);
    const Eigen::Matrix3d deviator = stress - stress.trace() / 3.0 * Eigen::Matrix3d::Identity();
    return std::sqrt(1.5 * deviator.squaredNorm());
}

} // namespace vox::sim
