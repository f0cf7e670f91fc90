// The warped factor preconditioner: it applies W A^-1 W^T (checked against a double-precision
// solve, unrotated and with every node turned), and it takes a new factor exactly when the CG
// iterations beyond those it needed right after the last one add up to the cost of a
// factorisation, or when one solve exceeds the hard cap, or when other dofs are held, or when the
// system grew and nothing said which of its rows changed. In the background, the new factor is
// swapped in exactly when the iterations since its launch add up to that cost, and it is corrected
// for the cuts made meanwhile.

#include "fem/rest_cholesky.hpp"

#include "fem/conjugate_gradient.hpp"
#include "fem/grid_laplacian.hpp"

#include <Eigen/Geometry>
#include <Eigen/SparseCholesky>
#include <gtest/gtest.h>

#include <chrono>
#include <cmath>
#include <stdexcept>
#include <thread>
#include <vector>

using namespace vox::fem;

namespace {

struct Fixture {
    SystemMatrix a = vox::test::grid_laplacian<Eigen::RowMajor>(5, 0.5, 3);
    std::vector<unsigned char> fixed = std::vector<unsigned char>(static_cast<std::size_t>(a.rows()), 0);
    std::vector<Eigen::Quaterniond> rest = std::vector<Eigen::Quaterniond>(static_cast<std::size_t>(a.rows() / 3), Eigen::Quaterniond::Identity());
};

/// Every node turned its own way (a uniform turn commutes with the isotropic grid Laplacian).
std::vector<Eigen::Quaterniond> scattered(std::size_t blocks)
{
    std::vector<Eigen::Quaterniond> q;
    for (std::size_t b = 0; b < blocks; ++b)
        q.emplace_back(Eigen::AngleAxisd(0.3 + 0.1 * static_cast<double>(b), Eigen::Vector3d(1.0, std::sin(static_cast<double>(b)), 0.5).normalized()));
    return q;
}

/// P r against W A^-1 W^T r, W the rotation of each block by q (relative error).
double warped_error(const RestCholesky& p, const SystemMatrix& a, const std::vector<Eigen::Quaterniond>& q, const Eigen::VectorXd& r)
{
    const Eigen::SimplicialLLT<Eigen::SparseMatrix<double>> exact{Eigen::SparseMatrix<double>(a)};
    Eigen::VectorXd turned = r;
    for (std::size_t b = 0; b < q.size(); ++b) turned.segment<3>(3 * static_cast<Eigen::Index>(b)) = q[b].conjugate() * r.segment<3>(3 * static_cast<Eigen::Index>(b));
    Eigen::VectorXd expected = exact.solve(turned);
    for (std::size_t b = 0; b < q.size(); ++b) expected.segment<3>(3 * static_cast<Eigen::Index>(b)) = q[b] * expected.segment<3>(3 * static_cast<Eigen::Index>(b)).eval();
    Eigen::VectorXd z;
    p.apply(r, z);
    return (z - expected).norm() / expected.norm();
}

/// Reports solves two iterations beyond a baseline of three until the factor is stale.
void wear_out(RestCholesky& p)
{
    p.report_iterations(3);
    for (int reports = 0; !p.needs_matrix(); ++reports) {
        ASSERT_LT(reports, 10000);
        p.report_iterations(5);
    }
}

/// A cut: the 8^3 grid's Laplacian with the nodes of a 2^3 corner numbered last (`grown`), and its
/// block over the other nodes (`small`). Growing from `small` to `grown` adds the corner's blocks
/// and changes the rows of the old nodes next to it (`changed`) only.
struct CornerCut {
    SystemMatrix small, grown;
    std::vector<std::uint32_t> changed;
};

CornerCut corner_cut(double shift)
{
    constexpr int m = 8;
    auto corner = [](int i, int j, int k) { return i >= m - 2 && j >= m - 2 && k >= m - 2; };
    Eigen::VectorXi order(3 * m * m * m); // order[dof of the cut system] = dof of the grid
    CornerCut cut;
    int next = 0;
    for (const bool last : {false, true})
        for (int i = 0; i < m; ++i)
            for (int j = 0; j < m; ++j)
                for (int k = 0; k < m; ++k) {
                    if (corner(i, j, k) != last) continue;
                    const int node = next++;
                    for (int d = 0; d < 3; ++d) order[3 * node + d] = 3 * ((i * m + j) * m + k) + d;
                    if (!last && (corner(i + 1, j, k) || corner(i, j + 1, k) || corner(i, j, k + 1))) cut.changed.push_back(static_cast<std::uint32_t>(node));
                }
    const Eigen::PermutationMatrix<Eigen::Dynamic> to_grid(order);
    const Eigen::SparseMatrix<double> a = vox::test::grid_laplacian(m, shift, 3);
    cut.grown = SystemMatrix(Eigen::SparseMatrix<double>(to_grid.transpose() * a * to_grid));
    const Eigen::Index old = 3 * (m * m * m - 8);
    cut.small = cut.grown.topLeftCorner(old, old);
    cut.grown.makeCompressed();
    cut.small.makeCompressed();
    return cut;
}

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
    RestCholesky p(Eigen::Matrix3d::Identity(), 25, INFINITY); // every factor in the frame: counted as taken
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
    EXPECT_EQ(p.correction_dofs(), 0u);
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

TEST(RestCholesky, FactorsInTheBackgroundAndSwapsAtTheIterationCount)
{
    Fixture f;
    RestCholesky p(Eigen::Matrix3d::Identity(), 25, 0.0); // however small, in the background
    p.update(&f.a, f.fixed, f.rest); // the first factor is taken in the frame
    const double cost = p.refactor_cost_iterations();
    ASSERT_GT(cost, 2.0);
    wear_out(p);
    // A stiffer matrix now, with every node turned: the snapshot the new factor is taken of.
    const SystemMatrix stiffer = vox::test::grid_laplacian<Eigen::RowMajor>(5, 1.5, 3);
    const std::vector<Eigen::Quaterniond> turned = scattered(f.rest.size());
    p.update(&stiffer, f.fixed, turned);
    EXPECT_TRUE(p.background_pending());
    EXPECT_FALSE(p.needs_matrix());
    EXPECT_EQ(p.factorizations(), 1);
    const Eigen::VectorXd r = Eigen::VectorXd::LinSpaced(f.a.rows(), -1.0, 2.0);
    // Until the swap the old factor, taken unturned, preconditions, warped to the turned nodes.
    EXPECT_LT(warped_error(p, f.a, turned, r), 1e-5);
    std::this_thread::sleep_for(std::chrono::milliseconds(50)); // most likely done: that must not bring the swap forward
    for (int reported = 1; reported < cost; ++reported) {
        p.report_iterations(1);
        p.update(nullptr, f.fixed, turned);
        ASSERT_TRUE(p.background_pending()) << reported << " of " << cost << " iterations";
        EXPECT_LT(warped_error(p, f.a, turned, r), 1e-5);
    }
    p.report_iterations(1); // the sum reaches the cost: the next update swaps
    EXPECT_TRUE(p.background_pending());
    p.update(nullptr, f.fixed, turned);
    EXPECT_FALSE(p.background_pending());
    EXPECT_EQ(p.factorizations(), 2);
    EXPECT_EQ(p.background_factorizations(), 1);
    EXPECT_FALSE(p.failed());
    // Taken at the turned state: no warp left, and the same as a factor taken in the frame.
    RestCholesky synchronous(Eigen::Matrix3d::Identity(), 25, INFINITY);
    synchronous.update(&stiffer, f.fixed, turned);
    Eigen::VectorXd z, expected;
    p.apply(r, z);
    synchronous.apply(r, expected);
    EXPECT_LT((z - expected).norm() / expected.norm(), 1e-6);
    EXPECT_LT(warped_error(p, stiffer, f.rest, r), 1e-5);
    // The rent-or-buy counters start again: the old baseline does not carry over.
    p.report_iterations(5);
    p.report_iterations(5);
    EXPECT_FALSE(p.needs_matrix());
}

TEST(RestCholesky, CorrectsTheBackgroundFactorForCutsMadeWhileItWasTaken)
{
    const CornerCut soft = corner_cut(0.5), cut = corner_cut(1.5);
    const auto blocks = [](const SystemMatrix& a) { return static_cast<std::size_t>(a.rows() / 3); };
    const std::vector<unsigned char> fixed(static_cast<std::size_t>(cut.small.rows()), 0), grown_fixed(static_cast<std::size_t>(cut.grown.rows()), 0);
    const std::vector<Eigen::Quaterniond> rest(blocks(cut.small), Eigen::Quaterniond::Identity()), grown_rest(blocks(cut.grown), Eigen::Quaterniond::Identity());
    RestCholesky p(Eigen::Matrix3d::Identity(), 25, 0.0); // however small, in the background
    p.update(&soft.small, fixed, rest);
    wear_out(p);
    p.update(&cut.small, fixed, rest); // launched, on a stiffer matrix
    ASSERT_TRUE(p.background_pending());
    // The cut, while the factorisation runs: the old factor is corrected meanwhile.
    p.blocks_changed(cut.changed);
    p.update(&cut.grown, grown_fixed, grown_rest);
    EXPECT_TRUE(p.background_pending());
    EXPECT_GT(p.correction_dofs(), 0u);
    for (int reported = 0; reported < p.refactor_cost_iterations(); reported += 4) p.report_iterations(4);
    p.update(&cut.grown, grown_fixed, grown_rest);
    ASSERT_FALSE(p.background_pending());
    EXPECT_EQ(p.factorizations(), 2);
    EXPECT_EQ(p.background_factorizations(), 1);
    EXPECT_GT(p.correction_dofs(), 0u);

    // As if the factor had been taken in the frame at the launch and corrected for the cut after it.
    RestCholesky synchronous(Eigen::Matrix3d::Identity(), 25, INFINITY);
    synchronous.update(&cut.small, fixed, rest);
    synchronous.blocks_changed(cut.changed);
    synchronous.update(&cut.grown, grown_fixed, grown_rest);
    EXPECT_EQ(synchronous.correction_dofs(), p.correction_dofs());
    const Eigen::VectorXd r = Eigen::VectorXd::LinSpaced(cut.grown.rows(), -1.0, 2.0).array().sin();
    Eigen::VectorXd z, expected;
    p.apply(r, z);
    synchronous.apply(r, expected);
    EXPECT_LT((z - expected).norm() / expected.norm(), 1e-6);
    // The grown system's inverse: the correction covers the rows the cut changed (CG
    // alone takes 26 iterations).
    Eigen::VectorXd x = Eigen::VectorXd::Zero(r.size());
    const CgResult cg = conjugate_gradient([&](const Eigen::VectorXd& v, Eigen::VectorXd& out) { out = cut.grown * v; },
                                           [&](const Eigen::VectorXd& v, Eigen::VectorXd& out) { p.apply(v, out); }, r,
                                           Eigen::VectorXd::Ones(r.size()), 1e-10, 100, x);
    EXPECT_LE(cg.residual, 1e-10);
    EXPECT_LE(cg.iterations, 10);
}

TEST(RestCholesky, CorrectedForACutItAppliesTheCutSystemsInverse)
{
    // The factor is taken before the cut; the cut adds the corner's nodes (new rows and columns)
    // and also changes the old rows beside them: their couplings among themselves halved, their
    // diagonals stiffened. Every node then turns the same way (which the isotropic system commutes
    // with), so the warped, corrected factor must apply exactly the cut system's inverse.
    const CornerCut cut = corner_cut(0.5);
    Eigen::SparseMatrix<double> after(cut.grown);
    std::vector<unsigned char> beside(static_cast<std::size_t>(after.rows() / 3), 0);
    for (const std::uint32_t b : cut.changed) beside[b] = 1;
    for (int col = 0; col < after.outerSize(); ++col)
        for (Eigen::SparseMatrix<double>::InnerIterator it(after, col); it; ++it) {
            const auto i = static_cast<std::size_t>(it.row() / 3), j = static_cast<std::size_t>(it.col() / 3);
            if (!beside[i] || !beside[j]) continue;
            if (i != j) it.valueRef() *= 0.5;
            else if (it.row() == it.col()) it.valueRef() += 0.7;
        }
    const SystemMatrix grown(after);
    const auto blocks = [](const SystemMatrix& a) { return static_cast<std::size_t>(a.rows() / 3); };
    const std::vector<unsigned char> fixed(static_cast<std::size_t>(cut.small.rows()), 0), grown_fixed(static_cast<std::size_t>(grown.rows()), 0);
    RestCholesky p(Eigen::Matrix3d::Identity(), 25, INFINITY);
    p.update(&cut.small, fixed, std::vector<Eigen::Quaterniond>(blocks(cut.small), Eigen::Quaterniond::Identity()));
    p.blocks_changed(cut.changed);
    const Eigen::Quaterniond turn(Eigen::AngleAxisd(0.4, Eigen::Vector3d(1, 2, 3).normalized()));
    ASSERT_TRUE(p.needs_matrix());
    p.update(&grown, grown_fixed, std::vector<Eigen::Quaterniond>(blocks(grown), turn));
    EXPECT_EQ(p.factorizations(), 1) << "corrected, not factored anew";
    EXPECT_EQ(p.correction_dofs(), 3 * (cut.changed.size() + 8));
    const Eigen::SimplicialLLT<Eigen::SparseMatrix<double>> exact(after);
    const Eigen::VectorXd r = Eigen::VectorXd::LinSpaced(grown.rows(), -1.0, 2.0).array().sin();
    Eigen::VectorXd z;
    p.apply(r, z);
    EXPECT_LT((z - exact.solve(r)).norm() / z.norm(), 1e-5); // the factor is applied in single precision
    // So CG converges at once (the grid Laplacian alone takes 26 iterations).
    Eigen::VectorXd x = Eigen::VectorXd::Zero(r.size());
    const CgResult cg = conjugate_gradient([&](const Eigen::VectorXd& v, Eigen::VectorXd& out) { out = grown * v; },
                                           [&](const Eigen::VectorXd& v, Eigen::VectorXd& out) { p.apply(v, out); }, r,
                                           Eigen::VectorXd::Ones(r.size()), 1e-10, 100, x);
    EXPECT_LE(cg.residual, 1e-10);
    EXPECT_LE(cg.iterations, 3);
}

TEST(RestCholesky, CorrectedForTheRowsWhoseContactTermsMoved)
{
    // The factor is taken while a tool presses block 5 (a stiff spring on its diagonal); by the
    // time the cut comes the tool presses block 9 instead. Told both, the correction applies the
    // inverse of the system as it is now.
    const CornerCut cut = corner_cut(0.5);
    const auto pressed = [](const SystemMatrix& a, std::uint32_t block) {
        Eigen::SparseMatrix<double> m(a);
        for (int i = 0; i < 3; ++i) m.coeffRef(3 * block + i, 3 * block + i) += 40.0;
        return m;
    };
    const SystemMatrix before(pressed(cut.small, 5));
    const Eigen::SparseMatrix<double> now = pressed(cut.grown, 9);
    const SystemMatrix grown(now);
    const std::vector<unsigned char> fixed(static_cast<std::size_t>(before.rows()), 0), grown_fixed(static_cast<std::size_t>(grown.rows()), 0);
    RestCholesky p(Eigen::Matrix3d::Identity(), 25, INFINITY);
    p.set_contact_blocks({5});
    p.update(&before, fixed, std::vector<Eigen::Quaterniond>(static_cast<std::size_t>(before.rows() / 3), Eigen::Quaterniond::Identity()));
    p.blocks_changed(cut.changed);
    p.set_contact_blocks({9});
    p.update(&grown, grown_fixed, std::vector<Eigen::Quaterniond>(static_cast<std::size_t>(grown.rows() / 3), Eigen::Quaterniond::Identity()));
    EXPECT_EQ(p.factorizations(), 1);
    EXPECT_EQ(p.correction_dofs(), 3 * (cut.changed.size() + 8 + 2));
    const Eigen::SimplicialLLT<Eigen::SparseMatrix<double>> exact(now);
    const Eigen::VectorXd r = Eigen::VectorXd::LinSpaced(grown.rows(), -1.0, 2.0).array().cos();
    Eigen::VectorXd z;
    p.apply(r, z);
    EXPECT_LT((z - exact.solve(r)).norm() / z.norm(), 1e-5);
}

TEST(RestCholesky, DiscardsABackgroundFactorWhenOtherDofsAreHeld)
{
    Fixture f;
    RestCholesky p(Eigen::Matrix3d::Identity(), 25, 0.0); // however small, in the background
    p.update(&f.a, f.fixed, f.rest);
    wear_out(p);
    p.update(&f.a, f.fixed, f.rest);
    ASSERT_TRUE(p.background_pending());
    f.fixed[0] = 1; // waits for the running factorisation, drops it and factors in the frame
    p.update(&f.a, f.fixed, f.rest);
    EXPECT_FALSE(p.background_pending());
    EXPECT_EQ(p.factorizations(), 3);
    EXPECT_EQ(p.background_factorizations(), 1);
    const Eigen::VectorXd r = Eigen::VectorXd::Ones(f.a.rows());
    Eigen::VectorXd z;
    p.apply(r, z);
    EXPECT_EQ(z[0], 0.0);

    // invalidate() during a run: the next update factors in the frame too.
    wear_out(p);
    p.update(&f.a, f.fixed, f.rest);
    ASSERT_TRUE(p.background_pending());
    p.invalidate();
    EXPECT_TRUE(p.needs_matrix());
    p.update(&f.a, f.fixed, f.rest);
    EXPECT_FALSE(p.background_pending());
    EXPECT_EQ(p.factorizations(), 5);
    EXPECT_EQ(p.background_factorizations(), 2);

    // Destroyed while a factorisation runs: it is waited for.
    wear_out(p);
    p.update(&f.a, f.fixed, f.rest);
    EXPECT_TRUE(p.background_pending());
}
