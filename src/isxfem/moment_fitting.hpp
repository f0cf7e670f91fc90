#pragma once
// Quadrature on cut tetrahedra by moment fitting (Mueller, Kummer, Oberlack, "Highly accurate
// surface and volume integration on implicit domains by means of moment-fitting", IJNME 96, 2013;
// the Is-XFEM paper's section 4.2): the points stay those of a fixed symmetric rule on the
// reference tetrahedron, and each side of a cut gets its own weights, solved so that the rule
// integrates every polynomial of degree <= 4 exactly over that side. Degree 4 is what the
// consistent mass of an enriched linear tetrahedron needs (products of two shape functions, each
// a linear function times a linear enrichment); the stiffness needs 2.
//
// Slivers: only the smaller side is fitted to its moments; the larger side's weights are the
// whole tetrahedron's minus the smaller side's, so a side of relative volume 1e-10 is integrated
// to machine precision relative to its own size, and the two sides always add up to the whole.

#include <Eigen/Core>

#include <array>
#include <vector>

namespace vox::isxfem {

class MomentFitting {
public:
    static constexpr int k_degree = 4;

    MomentFitting();

    /// The fixed points, reference coordinates: the 70 points of the symmetric degree-9
    /// Grundmann-Moeller rule.
    [[nodiscard]] const std::vector<Eigen::Vector3d>& points() const { return m_points; }
    /// Weights for the whole reference tetrahedron (sum 1/6).
    [[nodiscard]] const Eigen::VectorXd& whole() const { return m_whole; }
    /// The fitted polynomials: the monomials of degree <= 4 of 4 (x - 1/4), a basis of the same
    /// space as the plain monomials but with a Vandermonde matrix 80 times better conditioned
    /// (condition number 644 instead of 51,000 at these points).
    static constexpr double k_centre = 0.25, k_scale = 4.0;
    /// The minimum-norm weights that reproduce `moments` of that basis (monomial_exponents(4)
    /// order; monomial_moments(pieces, 4, k_centre, k_scale)).
    [[nodiscard]] Eigen::VectorXd fit(const Eigen::VectorXd& moments) const;

private:
    std::vector<Eigen::Vector3d> m_points;
    Eigen::MatrixXd m_pseudo_inverse; ///< points x monomials
    Eigen::VectorXd m_whole;
};

/// Weights of the two sides of the reference tetrahedron cut by the zero level of the linear
/// function with values `phi` at its vertices (phi < 0: negative side).
struct SideWeights {
    Eigen::VectorXd negative, positive;
    double negative_volume = 0.0, positive_volume = 0.0; ///< reference volumes, sum 1/6
};
SideWeights side_weights(const MomentFitting& fitting, const std::array<double, 4>& phi);

} // namespace vox::isxfem
