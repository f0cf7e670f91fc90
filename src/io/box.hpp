#pragma once
// The scenes' boxes (constraints, loads, wet regions, held pieces): closed, their boundary
// included up to rounding.

#include <Eigen/Core>

namespace vox::io {

/// Whether p lies in [lo, hi] (world mm), boundary included up to rounding.
[[nodiscard]] inline bool in_box(const Eigen::Vector3d& p_mm, const Eigen::Vector3d& lo, const Eigen::Vector3d& hi)
{
    const double tol = 1e-9 * (1.0 + lo.cwiseAbs().maxCoeff() + hi.cwiseAbs().maxCoeff());
    return (p_mm.array() >= lo.array() - tol).all() && (p_mm.array() <= hi.array() + tol).all();
}

} // namespace vox::io
