#include "isxfem/moment_fitting.hpp"

#include "isxfem/cut_tetrahedron.hpp"
#include "isxfem/simplex_rule.hpp"

#include <Eigen/QR>

namespace vox::isxfem {

MomentFitting::MomentFitting() : m_points(grundmann_moeller_tetrahedron(4).points)
{
    // The rows of V are the monomials at the points; min-norm weights w = V^+ m. The points
    // are unisolvent for degree 4 (the rule is exact to degree 9), so V has full row rank.
    const std::vector<std::array<int, 3>> exponents = monomial_exponents(k_degree);
    Eigen::MatrixXd v(static_cast<Eigen::Index>(exponents.size()), static_cast<Eigen::Index>(m_points.size()));
    for (std::size_t j = 0; j < exponents.size(); ++j)
        for (std::size_t q = 0; q < m_points.size(); ++q)
            v(static_cast<Eigen::Index>(j), static_cast<Eigen::Index>(q)) =
                monomial(exponents[j], k_scale * (m_points[q] - Eigen::Vector3d::Constant(k_centre)));
    m_pseudo_inverse = Eigen::CompleteOrthogonalDecomposition<Eigen::MatrixXd>(v).pseudoInverse();
    m_whole = fit(monomial_moments({whole_tetrahedron()}, k_degree, k_centre, k_scale));
}

Eigen::VectorXd MomentFitting::fit(const Eigen::VectorXd& moments) const { return m_pseudo_inverse * moments; }

SideWeights side_weights(const MomentFitting& fitting, const std::array<double, 4>& phi)
{
    const CutSides sides = split_reference_tetrahedron(phi);
    SideWeights w;
    w.negative_volume = sides.negative_volume();
    w.positive_volume = sides.positive_volume();
    const bool negative_smaller = w.negative_volume <= w.positive_volume;
    const Eigen::VectorXd small =
        fitting.fit(monomial_moments(negative_smaller ? sides.negative : sides.positive, MomentFitting::k_degree,
                                     MomentFitting::k_centre, MomentFitting::k_scale));
    (negative_smaller ? w.negative : w.positive) = small;
    (negative_smaller ? w.positive : w.negative) = fitting.whole() - small;
    // The larger side's volume likewise, so the two add up to 1/6 exactly as the weights do.
    (negative_smaller ? w.positive_volume : w.negative_volume) = 1.0 / 6.0 - (negative_smaller ? w.negative_volume : w.positive_volume);
    return w;
}

} // namespace vox::isxfem
