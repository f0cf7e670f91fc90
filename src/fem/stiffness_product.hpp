#pragma once
// An element's 24 x 24 stiffness times its 24 displacements, the inner loop of every matrix-free
// product and element pass.

#include "core/eigen_types.hpp"

namespace vox::fem {

/// k u, column by column into six independent sums of four rows. Eigen's product of these fixed
/// sizes runs each group of four rows as one chain of 24 dependent multiply-adds, so it waits on
/// their latency (576 cycles an element, most of a CG iteration on the FEM bench's beam); six
/// chains side by side keep the multiply-add units busy instead.
[[nodiscard]] inline Vector24d stiffness_times(const Matrix24d& k, const Vector24d& u)
{
    Eigen::Vector4d y0 = k.block<4, 1>(0, 0) * u[0], y1 = k.block<4, 1>(4, 0) * u[0], y2 = k.block<4, 1>(8, 0) * u[0];
    Eigen::Vector4d y3 = k.block<4, 1>(12, 0) * u[0], y4 = k.block<4, 1>(16, 0) * u[0], y5 = k.block<4, 1>(20, 0) * u[0];
    for (int j = 1; j < 24; ++j) {
        const double uj = u[j];
        y0.noalias() += k.block<4, 1>(0, j) * uj;
        y1.noalias() += k.block<4, 1>(4, j) * uj;
        y2.noalias() += k.block<4, 1>(8, j) * uj;
        y3.noalias() += k.block<4, 1>(12, j) * uj;
        y4.noalias() += k.block<4, 1>(16, j) * uj;
        y5.noalias() += k.block<4, 1>(20, j) * uj;
    }
    Vector24d y;
    y << y0, y1, y2, y3, y4, y5;
    return y;
}

} // namespace vox::fem
