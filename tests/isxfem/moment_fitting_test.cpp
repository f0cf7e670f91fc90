// Quadrature on cut tetrahedra. Random tetrahedra are cut by planes that leave a small side of
// relative volume 1e-1 down to 1e-10, in the three ways a plane can: a corner (one vertex alone),
// a wedge along an edge (two and two), a slab under a face (three vertices on the small side).
// Against a naive reference in quadruple precision (quad_reference.hpp):
//  - each side's exact moments (the pieces the sides are split into) agree to 1e-13;
//  - the moment-fitted weights integrate every monomial of degree <= 4 over each side to 1e-12;
// both relative to the side's own volume (every monomial lies in [0, 1] on the reference
// tetrahedron, so the side's volume bounds its moments). Cuts through vertices, edges and faces
// leave no NaN and sides that add up.

#include "isxfem/cut_tetrahedron.hpp"
#include "isxfem/moment_fitting.hpp"
#include "isxfem/simplex_rule.hpp"

#include "isxfem/quad_reference.hpp"

#include <Eigen/Geometry>
#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <string>

using namespace vox::isxfem;
using test::quad;

namespace {

enum class Kind { corner, edge, face };

struct CutCase {
    std::array<double, 4> phi{};
    std::string what;
};

/// A random tetrahedron cut by a plane whose negative side is a corner, edge wedge or face slab of
/// relative volume `fraction`; the cut function's values at the vertices.
CutCase random_cut(std::mt19937& rng, Kind kind, double fraction)
{
    std::uniform_real_distribution<double> u(-1.0, 1.0);
    std::array<Eigen::Vector3d, 4> x;
    do {
        for (Eigen::Vector3d& p : x) p = {u(rng), u(rng), u(rng)};
    } while (std::abs((x[1] - x[0]).cross(x[2] - x[0]).dot(x[3] - x[0])) < 0.1);
    Eigen::Vector3d n;
    if (kind == Kind::corner) {
        n = {u(rng), u(rng), u(rng)};
    } else if (kind == Kind::edge) { // level along edge (0, 1), rising towards vertices 2 and 3
        const Eigen::Vector3d e = (x[1] - x[0]).normalized();
        n = 0.5 * (x[2] + x[3]) - 0.5 * (x[0] + x[1]);
        n -= n.dot(e) * e;
        for (int k : {2, 3})
            if (n.dot(x[static_cast<std::size_t>(k)] - x[0]) <= 0.0) n += 2.0 * std::abs(n.dot(x[static_cast<std::size_t>(k)] - x[0])) * n.normalized();
    } else { // level along face (0, 1, 2), rising towards vertex 3
        n = (x[1] - x[0]).cross(x[2] - x[0]);
        if (n.dot(x[3] - x[0]) < 0.0) n = -n;
    }
    std::array<double, 4> h{};
    for (int k = 0; k < 4; ++k) h[static_cast<std::size_t>(k)] = n.dot(x[static_cast<std::size_t>(k)]);
    auto phi_at = [&](double d) {
        std::array<double, 4> phi{};
        for (int k = 0; k < 4; ++k) phi[static_cast<std::size_t>(k)] = h[static_cast<std::size_t>(k)] - d;
        return phi;
    };
    // The negative side grows with d: bisect for 6 x its reference volume = fraction.
    double lo = *std::min_element(h.begin(), h.end()), hi = *std::max_element(h.begin(), h.end());
    for (int it = 0; it < 200 && hi > lo; ++it) {
        const double mid = 0.5 * (lo + hi);
        if (mid == lo || mid == hi) break;
        (6.0 * split_reference_tetrahedron(phi_at(mid)).negative_volume() < fraction ? lo : hi) = mid;
    }
    const char* names[] = {"corner", "edge wedge", "face slab"};
    return {phi_at(0.5 * (lo + hi)), std::string(names[static_cast<int>(kind)]) + " of fraction " + std::to_string(fraction)};
}

double quad_volume(const std::vector<quad>& m) { return static_cast<double>(m[0]); } // the moment of 1

/// max_j |approx_j - exact_j| / volume.
double relative_error(const Eigen::VectorXd& approx, const std::vector<quad>& exact)
{
    const double volume = quad_volume(exact);
    double worst = 0.0;
    for (std::size_t j = 0; j < exact.size(); ++j)
        worst = std::max(worst, std::abs(static_cast<double>(static_cast<quad>(approx[static_cast<Eigen::Index>(j)]) - exact[j])) / volume);
    return worst;
}

Eigen::VectorXd integrate(const MomentFitting& fitting, const Eigen::VectorXd& weights)
{
    const auto e = monomial_exponents(MomentFitting::k_degree);
    Eigen::VectorXd m = Eigen::VectorXd::Zero(static_cast<Eigen::Index>(e.size()));
    for (std::size_t q = 0; q < fitting.points().size(); ++q)
        for (std::size_t j = 0; j < e.size(); ++j)
            m[static_cast<Eigen::Index>(j)] += weights[static_cast<Eigen::Index>(q)] * monomial(e[j], fitting.points()[q]);
    return m;
}

} // namespace

TEST(CutTetrahedron, QuadReferenceSidesAddUpToTheWhole)
{
    std::mt19937 rng(7);
    for (Kind kind : {Kind::corner, Kind::edge, Kind::face})
        for (double f : {0.3, 1e-4}) {
            const CutCase c = random_cut(rng, kind, f);
            const test::QuadMoments m = test::quad_moments(c.phi, 4);
            const auto e = monomial_exponents(4);
            for (std::size_t j = 0; j < e.size(); ++j) {
                const double exact = reference_tetrahedron_moment(e[j]);
                EXPECT_NEAR(static_cast<double>(m.negative[j] + m.positive[j]), exact, 1e-13 * exact) << c.what; // the rule's own rounding
            }
            EXPECT_NEAR(6.0 * quad_volume(m.negative), f, 1e-6 * f) << c.what;
        }
}

TEST(CutTetrahedron, SideMomentsAreExactForSlivers)
{
    std::mt19937 rng(11);
    for (Kind kind : {Kind::corner, Kind::edge, Kind::face})
        for (double f : {1e-1, 1e-2, 1e-4, 1e-6, 1e-8, 1e-10})
            for (int trial = 0; trial < 5; ++trial) {
                const CutCase c = random_cut(rng, kind, f);
                const CutSides sides = split_reference_tetrahedron(c.phi);
                const test::QuadMoments exact = test::quad_moments(c.phi, 4);
                EXPECT_LT(relative_error(monomial_moments(sides.negative, 4), exact.negative), 1e-13) << c.what;
                EXPECT_LT(relative_error(monomial_moments(sides.positive, 4), exact.positive), 1e-13) << c.what;
                EXPECT_NEAR(sides.negative_volume(), quad_volume(exact.negative), 1e-13 * quad_volume(exact.negative)) << c.what;
            }
}

TEST(MomentFitting, WeightsIntegrateDegreeFourExactlyOnBothSidesOfRandomCuts)
{
    const MomentFitting fitting;
    EXPECT_NEAR(fitting.whole().sum(), 1.0 / 6.0, 1e-15);
    std::mt19937 rng(3);
    double worst = 0.0;
    for (Kind kind : {Kind::corner, Kind::edge, Kind::face})
        for (double f : {1e-1, 1e-2, 1e-4, 1e-6, 1e-8, 1e-10})
            for (int trial = 0; trial < 5; ++trial) {
                const CutCase c = random_cut(rng, kind, f);
                const SideWeights w = side_weights(fitting, c.phi);
                const test::QuadMoments exact = test::quad_moments(c.phi, MomentFitting::k_degree);
                const double negative = relative_error(integrate(fitting, w.negative), exact.negative);
                const double positive = relative_error(integrate(fitting, w.positive), exact.positive);
                EXPECT_LT(negative, 1e-12) << c.what;
                EXPECT_LT(positive, 1e-12) << c.what;
                worst = std::max({worst, negative, positive});
                EXPECT_NEAR(w.negative_volume + w.positive_volume, 1.0 / 6.0, 1e-16);
            }
    std::printf("worst moment error over the random cuts, relative to the side's volume: %.2e\n", worst);
}

TEST(MomentFitting, CutsThroughVerticesEdgesAndFacesStayFinite)
{
    const MomentFitting fitting;
    // Zero at one vertex, two (a plane through an edge) and three (through a face), and tiny
    // values of either sign around them.
    for (double eps : {-1e-12, 0.0, 1e-12})
        for (const std::array<double, 4>& phi : {std::array<double, 4>{eps, 1.0, -1.0, 0.5}, std::array<double, 4>{eps, eps, -1.0, 1.0},
                                                 std::array<double, 4>{eps, eps, eps, 1.0}, std::array<double, 4>{-1.0, eps, eps, eps}}) {
            const SideWeights w = side_weights(fitting, phi);
            EXPECT_TRUE(w.negative.allFinite() && w.positive.allFinite());
            EXPECT_NEAR(w.negative_volume + w.positive_volume, 1.0 / 6.0, 1e-15);
            const test::QuadMoments exact = test::quad_moments(phi, MomentFitting::k_degree);
            EXPECT_NEAR(w.negative_volume, quad_volume(exact.negative), 1e-15);
            EXPECT_LT((integrate(fitting, w.negative) + integrate(fitting, w.positive) - integrate(fitting, fitting.whole())).norm(), 1e-15);
        }
}
