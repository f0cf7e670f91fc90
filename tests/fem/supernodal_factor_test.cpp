// The supernodal preconditioning factor: on a 3D grid Laplacian plus a mass term it solves to
// single precision (against a double simplicial factor), whatever the matrix's values after the
// first analysis; a singular matrix (no mass, nothing held) is refused.

#include "fem/supernodal_factor.hpp"

#include "fem/grid_laplacian.hpp"

#include <Eigen/SparseCholesky>
#include <gtest/gtest.h>

#include <vector>

using vox::test::grid_laplacian;

TEST(SupernodalFactor, SolvesToSinglePrecisionAndRefactorsNewValues)
{
    vox::fem::SupernodalFactor f;
    for (const double shift : {0.1, 2.0}) { // the same pattern, new values: factored without a new analysis
        const Eigen::SparseMatrix<double> a = grid_laplacian(12, shift);
        ASSERT_TRUE(f.factor(a, shift == 0.1));
        EXPECT_GT(f.entries(), static_cast<std::size_t>(a.nonZeros()) / 2);
        const Eigen::VectorXd b = Eigen::VectorXd::LinSpaced(a.rows(), -1.0, 2.0);
        Eigen::VectorXd x = b;
        f.solve(x);
        const Eigen::VectorXd exact = Eigen::SimplicialLLT<Eigen::SparseMatrix<double>>(a).solve(b);
        EXPECT_LT((x - exact).norm() / exact.norm(), 1e-5) << "shift " << shift;
        EXPECT_LT((a * x - b).norm() / b.norm(), 1e-4) << "shift " << shift;
    }
}

TEST(SupernodalFactor, RefusesASingularMatrix)
{
    vox::fem::SupernodalFactor f;
    EXPECT_FALSE(f.factor(grid_laplacian(6, 0.0), true)); // constants are in its null space
}
