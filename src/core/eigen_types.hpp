#pragma once
// Fixed-size Eigen types shared by the mechanics: 8-node hexahedra have 24 degrees of freedom.

#include <Eigen/Core>

namespace vox {

using Vector24d = Eigen::Matrix<double, 24, 1>;
using Matrix24d = Eigen::Matrix<double, 24, 24>;
using Matrix8d = Eigen::Matrix<double, 8, 8>;

} // namespace vox
