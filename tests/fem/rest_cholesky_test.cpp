// The warped factor preconditioner: it applies W A^-1 W^T (checked against a double-precision
// solve, unrotated and with every node turned), and it takes a new factor exactly when the CG
// iterations beyond those it needed right after the last one add up to the cost of a
// factorisation, or when one solve exceeds the hard cap, or when other dofs are held, or when the
// system grew and nothing said which of its rows changed.

#include "fem/rest_cholesky.hpp"

#include "fem/grid_laplacian.hpp"

#include <Eigen/Geometry>
#include <Eigen/SparseCholesky>
#include <gtest/gtest.h>

#include <cmath>
#include <stdexcept>
#include <vector>

using namespace vox::fem;

namespace {

struct Fixture {
    SystemMatrix a = vox::test::grid_laplacian<Eigen::RowMajor>(5, 0.5, 3);
    std::vector<unsigned char> fixed = std::vector<unsigned char>(static_cast<std::size_t>(a.rows()), 0);
    std::vector<Eigen::Quaterniond> rest = std::vector<Eigen::Quaterniond>(static_cast<std::size_t>(a.rows() / 3), Eigen::Quaterniond::Identity());
};

} // namespace

TEST(RestCholesky, AppliesTheWarpedInverse)
{
    Fixture f;
    RestCholesky p(Eigen::Matrix3d::Identity());
    ASSERT_TRUE(p.needs_matrix());
    p.update(&f.a, f.fixed, f.rest);
    ASSERT_FALSE(p.failed());
    const Eigen::VectorXd r = Eigen::VectorXd::LinSpaced(f.a.rows(), -1.0, 2.0);
    const Eigen::SimplicialLLT<Eigen::SparseMatrix<double>> exact{Eigen::SparseMatrix<double>(f.a)};
    Eigen::VectorXd z;
    p.apply(r, z);
    const Eigen::VectorXd expected = exact.solve(r);
    EXPECT_LT((z - expected).norm() / expected.norm(), 1e-5);

    // Every node turned by q: P = W A^-1 W^T with W = diag(q).
    const Eigen::Quaterniond q(Eigen::AngleAxisd(0.7, Eigen::Vector3d(1, -2, 0.5).normalized()));
    p.update(nullptr, f.fixed, std::vector<Eigen::Quaterniond>(f.rest.size(), q)); // no new factor: no matrix needed
    p.apply(r, z);
    const Eigen::Matrix3d w = q.toRotationMatrix();
    Eigen::VectorXd rotated = r;
    for (Eigen::Index i = 0; i < r.size(); i += 3) rotated.segment<3>(i) = w.transpose() * r.segment<3>(i);
    Eigen::VectorXd turned = exact.solve(rotated);
    for (Eigen::Index i = 0; i < r.size(); i += 3) turned.segment<3>(i) = w * turned.segment<3>(i).eval();
    EXPECT_LT((z - turned).norm() / turned.norm(), 1e-5);
    EXPECT_EQ(p.factorizations(), 1);
}

TEST(RestCholesky, RefactorsWhenTheExcessIterationsPayForIt)
{
    Fixture f;
    RestCholesky p(Eigen::Matrix3d::Identity(), 25);
    p.update(&f.a, f.fixed, f.rest);
    const double cost = p.refactor_cost_iterations();
    ASSERT_GT(cost, 2.0);
    p.report_iterations(3); // the baseline
    int reports = 0;
    while (!p.needs_matrix()) {
        p.report_iterations(5); // two beyond the baseline each time
        ++reports;
        ASSERT_LT(reports, 10000);
    }
    EXPECT_EQ(reports, static_cast<int>(std::ceil(cost / 2.0)));
    EXPECT_THROW(p.update(nullptr, f.fixed, f.rest), std::logic_error);
    p.update(&f.a, f.fixed, f.rest);
    EXPECT_EQ(p.factorizations(), 2);
    EXPECT_FALSE(p.needs_matrix());

    p.report_iterations(26); // beyond the hard cap: stale at once
    EXPECT_TRUE(p.needs_matrix());
    p.update(&f.a, f.fixed, f.rest);

    p.report_iterations(4);
    p.report_iterations(2); // fewer than the baseline: the new baseline, no excess
    for (int k = 0; k < static_cast<int>(cost) + 5; ++k) p.report_iterations(2);
    EXPECT_FALSE(p.needs_matrix());

    f.fixed[0] = 1; // other dofs held: a new factor even though nothing asked for one
    p.update(&f.a, f.fixed, f.rest);
    EXPECT_EQ(p.factorizations(), 4);
}

TEST(RestCholesky, AGrownSystemIsFactoredAnewUnlessToldWhatChanged)
{
    Fixture small;
    RestCholesky p(Eigen::Matrix3d::Identity());
    p.update(&small.a, small.fixed, small.rest);
    // The same kind of system with more nodes: nothing said which rows changed, so a new factor.
    const SystemMatrix grown = vox::test::grid_laplacian<Eigen::RowMajor>(6, 0.5, 3);
    const std::vector<unsigned char> fixed(static_cast<std::size_t>(grown.rows()), 0);
    const std::vector<Eigen::Quaterniond> rest(static_cast<std::size_t>(grown.rows() / 3), Eigen::Quaterniond::Identity());
    p.update(&grown, fixed, rest);
    EXPECT_EQ(p.factorizations(), 2);
    EXPECT_EQ(p.patch_dofs(), 0u);
    Eigen::VectorXd z;
    p.apply(Eigen::VectorXd::Ones(grown.rows()), z);
    const Eigen::SimplicialLLT<Eigen::SparseMatrix<double>> exact{Eigen::SparseMatrix<double>(grown)};
    const Eigen::VectorXd expected = exact.solve(Eigen::VectorXd::Ones(grown.rows()));
    EXPECT_LT((z - expected).norm() / expected.norm(), 1e-5);
}

TEST(RestCholesky, WarpsAJumpBlockWithTheTwoSidesOfItsCrack)
{
    // Blocks 0 .. n-1 of a grid Laplacian; block 1 is the jump of node 0 across a crack (the
    // node on side 0). The node turns by r0, the far side by r1: P must be W A^-1 W^T with
    // W = [r0 0; (r1 - r0) r1] on (node, jump) and the other blocks turned by their own rotation.
    Fixture f;
    RestCholesky p(Eigen::Matrix3d::Identity());
    p.set_jump_blocks({JumpBlock{1, 0, 1.0}});
    p.update(&f.a, f.fixed, f.rest);
    const Eigen::Quaterniond q0(Eigen::AngleAxisd(0.4, Eigen::Vector3d(1, 2, 3).normalized()));
    const Eigen::Quaterniond q1(Eigen::AngleAxisd(1.1, Eigen::Vector3d(-2, 0, 1).normalized()));
    std::vector<Eigen::Quaterniond> rotation(f.rest.size(), q0);
    rotation[1] = q1;
    p.update(nullptr, f.fixed, rotation);
    const Eigen::Index n = f.a.rows();
    Eigen::MatrixXd w = Eigen::MatrixXd::Zero(n, n);
    for (Eigen::Index b = 0; b < n / 3; ++b) w.block<3, 3>(3 * b, 3 * b) = rotation[static_cast<std::size_t>(b)].toRotationMatrix();
    w.block<3, 3>(3, 0) = q1.toRotationMatrix() - q0.toRotationMatrix();
    const Eigen::MatrixXd inverse = Eigen::MatrixXd(f.a).inverse();
    const Eigen::MatrixXd expected = w * inverse * w.transpose();
    const Eigen::VectorXd r = Eigen::VectorXd::LinSpaced(n, -1.0, 2.0);
    Eigen::VectorXd z;
    p.apply(r, z);
    EXPECT_LT((z - expected * r).norm() / (expected * r).norm(), 1e-5);
    EXPECT_EQ(p.factorizations(), 1);
    // With the sign for a node on side 1: W_jump,node = -(r_jump - r_node).
    p.set_jump_blocks({JumpBlock{1, 0, -1.0}});
    p.update(nullptr, f.fixed, rotation);
    w.block<3, 3>(3, 0) *= -1.0;
    p.apply(r, z);
    const Eigen::VectorXd flipped = w * inverse * w.transpose() * r;
    EXPECT_LT((z - flipped).norm() / flipped.norm(), 1e-5);
}
