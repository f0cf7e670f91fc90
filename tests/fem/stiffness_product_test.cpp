// An element's stiffness times its displacements, summed column by column in six groups of four
// rows, against Eigen's own product of the same matrices: the same numbers to round-off, on
// random matrices (nothing in the sum may assume symmetry).

#include "fem/stiffness_product.hpp"

#include <gtest/gtest.h>

#include <random>

namespace vox::fem {
namespace {

TEST(StiffnessProduct, EqualsEigensProductToRoundOff)
{
    std::mt19937 rng(7);
    std::uniform_real_distribution<double> value(-1.0, 1.0);
    for (int trial = 0; trial < 20; ++trial) {
        Matrix24d k;
        Vector24d u;
        for (int i = 0; i < 24; ++i) {
            u[i] = value(rng);
            for (int j = 0; j < 24; ++j) k(i, j) = 1e5 * value(rng);
        }
        const Vector24d expected = k * u;
        const Vector24d got = stiffness_times(k, u);
        EXPECT_LT((got - expected).norm(), 1e-12 * k.norm() * u.norm()) << "trial " << trial;
    }
}

} // namespace
} // namespace vox::fem
