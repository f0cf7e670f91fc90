// The supernodal preconditioning factor: on a 3D grid Laplacian plus a mass term it solves to
// single precision (against a double simplicial factor), whatever the matrix's values after the
// first analysis; a singular matrix (no mass, nothing held) is refused, and a failure names its
// dof and the note a solver gives says only what the system shows. The solves split over threads
// give the same answer as on one.

#include "fem/supernodal_factor.hpp"

#include "fem/factor_failure.hpp"
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
    EXPECT_TRUE(f.failure().failed);
    EXPECT_FALSE(f.failure().not_positive_definite); // singular, not indefinite
    EXPECT_LT(f.failure().pivot_ratio, 1e-10);
    EXPECT_GE(f.failure().dof, 0);
    EXPECT_LT(f.failure().dof, 216);
    // The same pattern with values that factor: the analysis is kept, and the solves are planned
    // for it now.
    const Eigen::SparseMatrix<double> a = grid_laplacian(6, 0.5);
    ASSERT_TRUE(f.factor(a, false));
    const Eigen::VectorXd b = Eigen::VectorXd::LinSpaced(a.rows(), -1.0, 2.0);
    Eigen::VectorXd x = b;
    f.solve(x);
    EXPECT_LT((a * x - b).norm() / b.norm(), 1e-4);
    EXPECT_FALSE(f.failure().failed);
}

TEST(SupernodalFactor, NamesTheDofWhosePivotIsNotPositive)
{
    // One negative diagonal entry in an otherwise positive definite matrix: eliminating other
    // rows only lowers its pivot (the off-diagonals are negative), so the factorisation stops
    // there, whatever order the analysis chose.
    Eigen::SparseMatrix<double> a = grid_laplacian(8, 0.5);
    const int bad = 301;
    a.coeffRef(bad, bad) = -2.0;
    vox::fem::SupernodalFactor f;
    EXPECT_FALSE(f.factor(a, true));
    EXPECT_TRUE(f.failure().failed);
    EXPECT_TRUE(f.failure().not_positive_definite);
    EXPECT_EQ(f.failure().dof, bad);
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

TEST(SupernodalFactor, TheFallbackNoteSaysWhatFailedWhereAndOnlyTheCauseTheSystemShows)
{
    using vox::fem::fallback_note;
    const Eigen::Vector3d at(0.0123, -0.004, 0.1);
    const vox::fem::FactorFailure indefinite{true, true, 7, 0.0};
    EXPECT_EQ(fallback_note("warped Cholesky", indefinite, &at, false, true),
              "warped Cholesky preconditioner failed: the step's matrix is not positive definite at the node at (12.3, -4.0, 100.0) mm; "
              "using Jacobi");
    const vox::fem::FactorFailure singular{true, false, 7, 3e-14};
    const std::string free = fallback_note("warped Cholesky", singular, nullptr, true, false);
    EXPECT_EQ(free, "warped Cholesky preconditioner failed: the step's matrix is nearly singular (smallest pivot 3.0e-14 of the largest) "
                    "(nothing holds the object); using Jacobi");
    EXPECT_NE(fallback_note("c", singular, nullptr, true, true).find("(a piece that nothing holds?)"), std::string::npos);
    // With mass, M/h^2 keeps the matrix regular whatever holds the object: no hold is suggested.
    EXPECT_EQ(fallback_note("c", singular, nullptr, false, false).find("holds"), std::string::npos);
    EXPECT_EQ(fallback_note("c", {true, false, -1, 0.0}, nullptr, false, true), "c preconditioner failed: the step's matrix is singular; using Jacobi");
}
