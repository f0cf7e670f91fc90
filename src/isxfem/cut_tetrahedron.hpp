#pragma once
// The reference tetrahedron (0,0,0), (1,0,0), (0,1,0), (0,0,1) split by the zero level of a linear
// function (a planar cut, given by its values at the four vertices) into its two sides, each a
// union of tetrahedra, and the exact moments of monomials over a side.
//
// Slivers stay exact: each piece keeps its corner and three edge vectors computed from the
// vertices of the reference tetrahedron (whose differences are exact) and the cut fractions
// along its edges, never as differences of rounded points. A side of relative volume 1e-12 has
// its volume and moments to about machine precision relative to its own size.

#include <Eigen/Core>

#include <array>
#include <vector>

namespace vox::isxfem {

/// A tetrahedron as a corner and its three edge vectors, reference coordinates, with its volume
/// (computed more carefully than det(edges) / 6 would be for a sliver).
struct Piece {
    Eigen::Vector3d corner = Eigen::Vector3d::Zero();
    Eigen::Matrix3d edges = Eigen::Matrix3d::Zero(); ///< columns: the other corners minus `corner`
    double volume = 0.0;
};

/// The two sides of the cut: phi < 0 and phi >= 0 (a vertex on the plane counts as positive).
struct CutSides {
    std::vector<Piece> negative, positive;
    [[nodiscard]] double negative_volume() const;
    [[nodiscard]] double positive_volume() const;
};

/// `phi`: the cut function's values at the reference vertices 0..3.
CutSides split_reference_tetrahedron(const std::array<double, 4>& phi);

/// The integrals of the monomials of degree <= p (monomial_exponents(p) order) of the shifted and
/// scaled coordinates scale * (x - centre) over `pieces`: exact up to rounding (a
/// Grundmann-Moeller rule exact to degree p on each piece).
Eigen::VectorXd monomial_moments(const std::vector<Piece>& pieces, int p, double centre = 0.0, double scale = 1.0);
/// The whole reference tetrahedron as a piece.
Piece whole_tetrahedron();

} // namespace vox::isxfem
