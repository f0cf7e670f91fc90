#pragma once
// Quadrature on simplices, generated rather than tabulated: the Grundmann-Moeller rules (A.
// Grundmann, H. M. Moeller, "Invariant integration formulas for the n-simplex by combinatorial
// methods", SIAM J. Numer. Anal. 15, 1978), exact for polynomials of degree 2s + 1 on the
// reference triangle or tetrahedron, symmetric under the simplex's vertex permutations (some
// weights are negative). And the monomials x^a y^b z^c of total degree <= p with their exact
// integrals over the reference tetrahedron.

#include <Eigen/Core>

#include <array>
#include <vector>

namespace vox::isxfem {

/// Points in reference coordinates and weights summing to the reference simplex's measure.
struct SimplexRule {
    std::vector<Eigen::Vector3d> points; ///< tetrahedron: (x, y, z); triangle: (x, y, 0)
    std::vector<double> weights;
};

/// The reference tetrahedron (0,0,0), (1,0,0), (0,1,0), (0,0,1), volume 1/6: degree 2s + 1.
SimplexRule grundmann_moeller_tetrahedron(int s);
/// The reference triangle (0,0), (1,0), (0,1), area 1/2: degree 2s + 1.
SimplexRule grundmann_moeller_triangle(int s);

/// The exponents (a, b, c) of the monomials of total degree <= p, by degree then lexicographically;
/// (p + 1)(p + 2)(p + 3) / 6 of them.
std::vector<std::array<int, 3>> monomial_exponents(int p);

/// x^a y^b z^c.
double monomial(const std::array<int, 3>& e, const Eigen::Vector3d& x);

/// The exact integral of x^a y^b z^c over the reference tetrahedron: a! b! c! / (a + b + c + 3)!.
double reference_tetrahedron_moment(const std::array<int, 3>& e);

} // namespace vox::isxfem
