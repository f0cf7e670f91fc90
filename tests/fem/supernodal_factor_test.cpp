// The supernodal preconditioning factor: on a 3D grid Laplacian plus a mass term it solves to
// single precision (against a double simplicial factor), whatever the matrix's values after the
// first analysis; a singular matrix (no mass, nothing held) is refused. The solves split over
// threads give the same answer as on one.

#include "fem/supernodal_factor.hpp"

#include "fem/grid_laplacian.hpp"

#include <Eigen/SparseCholesky>
#include <gtest/gtest.h>
#include <tbb/task_arena.h>

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
    // The same pattern with values that factor: the analysis is kept, and the solves are planned
    // for it now.
    const Eigen::SparseMatrix<double> a = grid_laplacian(6, 0.5);
    ASSERT_TRUE(f.factor(a, false));
    const Eigen::VectorXd b = Eigen::VectorXd::LinSpaced(a.rows(), -1.0, 2.0);
    Eigen::VectorXd x = b;
    f.solve(x);
    EXPECT_LT((a * x - b).norm() / b.norm(), 1e-4);
}

TEST(SupernodalFactor, SolvesOnSeveralThreadsAsOnOne)
{
    const Eigen::SparseMatrix<double> a = grid_laplacian(14, 0.05, 3);
    const Eigen::VectorXd b = Eigen::VectorXd::LinSpaced(a.rows(), -1.0, 2.0).array().sin();
    const Eigen::VectorXd exact = Eigen::SimplicialLLT<Eigen::SparseMatrix<double>>(a).solve(b);
    std::vector<Eigen::VectorXd> solved;
    for (const int threads : {1, 2}) {
        tbb::task_arena(threads).execute([&] {
            vox::fem::SupernodalFactor f;
            ASSERT_TRUE(f.factor(a, true));
            if (threads == 1) {
                EXPECT_EQ(f.parallel_groups(), 0u); // serial: everything is the top
            } else {
                EXPECT_EQ(f.parallel_groups(), static_cast<std::size_t>(threads));
                EXPECT_GT(f.top_share(), 0.0);
                EXPECT_LT(f.top_share(), 0.5) << "the serial top should be the smaller part of the work";
            }
            Eigen::VectorXd x = b;
            for (int repeat = 0; repeat < 2; ++repeat) { // the scratch is reset between solves
                x = b;
                f.solve(x);
            }
            EXPECT_LT((x - exact).norm() / exact.norm(), 1e-5) << threads << " threads";
            solved.push_back(x);
        });
    }
    EXPECT_LT((solved[1] - solved[0]).norm() / solved[0].norm(), 1e-6); // only the float sums' order differs
}
