#pragma once
// Linear tetrahedra, whole and cut once with the Is-XFEM enrichment (Wu and Li 2015; the Is-XFEM
// sculpting paper, section 4.1, equations 3 to 8): for a cut with level function phi and node
// sides H_i = H(phi(x_i)) (H = 1 where phi >= 0, else 0),
//   psi_i(x) = H(phi(x)) - [k gamma(x) + (1 - k) H_i],   gamma(x) = sum_m N_m(x) H_m,
// and the displacement u = sum_i N_i u_i + sum_i psi_i N_i a_i. k = 0 is the shifted-Heaviside
// XFEM of Koschier et al. 2017; k > 0 keeps every enriched function away from zero on both sides
// (on the side of its node it is k (1 - gamma) or -k gamma), which is what bounds the condition
// number when a cut passes close to a node.
//
// On each side the integrands are polynomials: the stiffness's of degree 2, the consistent mass's
// of degree 4, integrated by the moment-fitted weights of that side (moment_fitting.hpp).
//
// What the enrichment can represent: each side translating on its own, for any k (a_i = t,
// u_i = H_i t moves the positive side by t). Each side rotating on its own only for k = 0: for
// k > 0 the term k gamma d(x) is quadratic when the jump d is not constant, so pieces turning
// apart inside a cut element meet a spurious stiffness of order k^2 (measured in the tests).

#include "isxfem/moment_fitting.hpp"

#include "grid/hex8.hpp"

#include <Eigen/Core>

#include <array>
#include <vector>

namespace vox::isxfem {

using Matrix12d = Eigen::Matrix<double, 12, 12>;
using Matrix24d = Eigen::Matrix<double, 24, 24>;

/// Shape function gradients (rows, 1/m) and volume (m^3) of a tetrahedron at rest.
struct TetGeometry {
    Eigen::Matrix<double, 4, 3> gradient;
    double volume = 0.0;
};
TetGeometry tet_geometry(const std::array<Eigen::Vector3d, 4>& x);

/// Linear elastic stiffness of a whole tetrahedron, N/m (dofs: 3 per node, node-major).
Matrix12d tet_stiffness(const TetGeometry& g, const grid::Lame& lame);
/// Consistent mass of a whole tetrahedron, kg: rho V (1 + delta_ij) / 20 per axis.
Matrix12d tet_mass(const TetGeometry& g, double density);

/// A tetrahedron cut once: matrices over [u_0 .. u_3, a_0 .. a_3] (standard then enriched, 3
/// dofs each).
struct CutTet {
    Matrix24d stiffness = Matrix24d::Zero(), mass = Matrix24d::Zero();
    std::array<Matrix24d, 2> side_stiffness{Matrix24d::Zero(), Matrix24d::Zero()}; ///< their sum is `stiffness`
    std::array<double, 2> side_volume{};    ///< m^3: phi < 0, phi >= 0
    std::array<unsigned char, 4> node_side{}; ///< H_i
};

/// `phi`: the cut's level function at the four nodes (linear in the tetrahedron); `k` in [0, 1].
CutTet cut_tet(const std::array<Eigen::Vector3d, 4>& x, const std::array<double, 4>& phi, double k, const grid::Lame& lame,
               double density, const MomentFitting& fitting);

/// A non-empty region of a tetrahedron cut by several planes: its side of each cut (bit j for cut
/// j), its volume and its stiffness at rest over the element's dofs.
struct Region {
    unsigned pattern = 0;
    double volume = 0.0; ///< m^3
    Eigen::MatrixXd stiffness;
};

/// A tetrahedron cut by several planes, the cuts' enrichments added: matrices over [u_0 .. u_3,
/// then per cut j its a_0 .. a_3].
struct MultiCutTet {
    std::vector<Region> regions;                         ///< the non-empty ones
    Eigen::MatrixXd mass;                                ///< kg
    std::vector<std::array<unsigned char, 4>> node_side; ///< per cut, H_i
};

/// `phi`: per cut its level function at the four nodes. Each region is clipped out of the
/// tetrahedron plane by plane (split_reference_tetrahedron) and its integrands, polynomials of
/// degree 4 at most, integrated exactly on its pieces by a Grundmann-Moeller rule of degree 5
/// (each region directly, so a small one is as accurate as a large one).
MultiCutTet multi_cut_tet(const std::array<Eigen::Vector3d, 4>& x, const std::vector<std::array<double, 4>>& phi, double k,
                          const grid::Lame& lame, double density);

} // namespace vox::isxfem
