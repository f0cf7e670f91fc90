// The supernodal preconditioning factor: on a 3D grid Laplacian plus a mass term it solves to
// single precision (against a double simplicial factor), whatever the matrix's values after the
// first analysis; a singular matrix (no mass, nothing held) is refused.

#include "fem/supernodal_factor.hpp"

#include <Eigen/SparseCholesky>
#include <gtest/gtest.h>

#include <tuple>
#include <vector>

namespace {

/// The 7-point Laplacian on an n^3 grid (Neumann boundaries) plus `shift` times the identity.
Eigen::SparseMatrix<double> grid_laplacian(int n, double shift)
{
    std::vector<Eigen::Triplet<double>> t;
    auto id = [n](int i, int j, int k) { return (i * n + j) * n + k; };
    auto inside = [n](int i, int j, int k) { return i >= 0 && j >= 0 && k >= 0 && i < n && j < n && k < n; };
    for (int i = 0; i < n; ++i)
        for (int j = 0; j < n; ++j)
            for (int k = 0; k < n; ++k) {
                double degree = 0.0;
                for (const auto& [di, dj, dk] : {std::tuple{1, 0, 0}, std::tuple{-1, 0, 0}, std::tuple{0, 1, 0}, std::tuple{0, -1, 0},
                                                 std::tuple{0, 0, 1}, std::tuple{0, 0, -1}})
                    if (inside(i + di, j + dj, k + dk)) {
                        t.emplace_back(id(i, j, k), id(i + di, j + dj, k + dk), -1.0);
                        degree += 1.0;
                    }
                t.emplace_back(id(i, j, k), id(i, j, k), degree + shift);
            }
    Eigen::SparseMatrix<double> m(n * n * n, n * n * n);
    m.setFromTriplets(t.begin(), t.end());
    m.makeCompressed();
    return m;
}

} // namespace

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
