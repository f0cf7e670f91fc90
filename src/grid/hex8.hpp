#pragma once
// The 8-node trilinear hexahedron on an axis-aligned box: stiffness (isotropic linear elasticity)
// and consistent mass, integrated exactly with 2 x 2 x 2 Gauss points (the integrands are at most
// quadratic along each axis). Corner c has its bits (c & 1, c & 2, c & 4) = (+x, +y, +z); degree of
// freedom 3 c + axis. SI units: box edges in metres, K in N/m, M in kg.

#include "core/eigen_types.hpp"

namespace vox::grid {

/// Lame parameters of an isotropic material: lambda = E nu / ((1 + nu)(1 - 2 nu)), mu = E / (2 (1 + nu)), Pa.
struct Lame {
    double lambda = 0.0;
    double mu = 0.0;
};
[[nodiscard]] Lame lame_from_young_poisson(double youngs_modulus_pa, double poisson_ratio);

/// Shape function N_c at local coordinates t in [0, 1]^3.
[[nodiscard]] double hex8_shape(int corner, const Eigen::Vector3d& t);

/// Stiffness of a box of edges `size_m` (24 x 24, symmetric positive semi-definite, null space
/// the 6 rigid motions).
[[nodiscard]] Matrix24d hex8_stiffness(const Eigen::Vector3d& size_m, const Lame& material);

/// Consistent scalar mass of a box (8 x 8, rho * integral of N_c N_d); the full 24 x 24 mass is
/// this matrix times the 3 x 3 identity, per axis.
[[nodiscard]] Matrix8d hex8_mass(const Eigen::Vector3d& size_m, double density_kg_m3);

/// Expands a scalar 8 x 8 nodal matrix to 24 x 24 (each entry times the 3 x 3 identity).
[[nodiscard]] Matrix24d expand_to_dofs(const Matrix8d& scalar);

} // namespace vox::grid
