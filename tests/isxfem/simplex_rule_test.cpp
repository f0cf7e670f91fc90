// The generated Grundmann-Moeller rules integrate every monomial up to their degree exactly on the
// reference tetrahedron and triangle (closed forms a! b! c! / (a + b + c + 3)! and
// a! b! / (a + b + 2)!; to 1e-13, the higher rules' alternating weights cancel), and fail at the
// next degree (so the degree claimed is the real one).

#include "isxfem/simplex_rule.hpp"

#include <gtest/gtest.h>

#include <cmath>

using namespace vox::isxfem;

namespace {

double factorial(int n) { return n <= 1 ? 1.0 : n * factorial(n - 1); }

double rule_moment(const SimplexRule& rule, const std::array<int, 3>& e)
{
    double sum = 0.0;
    for (std::size_t q = 0; q < rule.points.size(); ++q) sum += rule.weights[q] * monomial(e, rule.points[q]);
    return sum;
}

} // namespace

TEST(SimplexRule, TetrahedronRulesAreExactToTheirDegree)
{
    for (int s = 0; s <= 4; ++s) {
        const SimplexRule rule = grundmann_moeller_tetrahedron(s);
        const int degree = 2 * s + 1;
        for (const auto& e : monomial_exponents(degree)) {
            const double exact = reference_tetrahedron_moment(e);
            EXPECT_NEAR(rule_moment(rule, e), exact, 1e-13 * exact) << "s " << s << " x^" << e[0] << " y^" << e[1] << " z^" << e[2];
        }
        // Degree 2s + 2 is beyond it: x^(2s+2) is not integrated exactly.
        const std::array<int, 3> beyond{degree + 1, 0, 0};
        EXPECT_GT(std::abs(rule_moment(rule, beyond) - reference_tetrahedron_moment(beyond)), 1e-8 * reference_tetrahedron_moment(beyond));
    }
    EXPECT_EQ(grundmann_moeller_tetrahedron(4).points.size(), 70u); // 35 + 20 + 10 + 4 + 1
}

TEST(SimplexRule, TriangleRulesAreExactToTheirDegree)
{
    for (int s = 0; s <= 3; ++s) {
        const SimplexRule rule = grundmann_moeller_triangle(s);
        for (int a = 0; a <= 2 * s + 1; ++a)
            for (int b = 0; a + b <= 2 * s + 1; ++b) {
                const double exact = factorial(a) * factorial(b) / factorial(a + b + 2);
                EXPECT_NEAR(rule_moment(rule, {a, b, 0}), exact, 1e-14 * exact) << "s " << s << " x^" << a << " y^" << b;
            }
        for (const Eigen::Vector3d& p : rule.points) EXPECT_EQ(p.z(), 0.0);
    }
}

TEST(SimplexRule, MonomialsAreCountedByDegree)
{
    EXPECT_EQ(monomial_exponents(2).size(), 10u);
    EXPECT_EQ(monomial_exponents(4).size(), 35u);
    EXPECT_DOUBLE_EQ(monomial({2, 1, 0}, Eigen::Vector3d(3, 5, 7)), 45.0);
    EXPECT_DOUBLE_EQ(reference_tetrahedron_moment({0, 0, 0}), 1.0 / 6.0);
}
