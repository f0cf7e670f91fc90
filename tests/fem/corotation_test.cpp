// The rotation of a corotational element against the polar factor of an SVD: from identity, from a
// warm start a step away and from a start far away, for stretched and sheared gradients; an
// inverted gradient gives a proper rotation that aligns at least as well as any of the other
// proper candidates of its SVD.

#include "fem/corotation.hpp"

#include <Eigen/SVD>
#include <gtest/gtest.h>

#include <array>
#include <limits>
#include <random>

using namespace vox::fem;

namespace {

Eigen::Matrix3d polar(const Eigen::Matrix3d& a)
{
    const Eigen::JacobiSVD<Eigen::Matrix3d> svd(a, Eigen::ComputeFullU | Eigen::ComputeFullV);
    return svd.matrixU() * svd.matrixV().transpose();
}

} // namespace

TEST(Corotation, ExtractsThePolarRotationFromAnyStart)
{
    std::mt19937 random(11);
    std::uniform_real_distribution<double> u(-1.0, 1.0);
    for (int trial = 0; trial < 200; ++trial) {
        const Eigen::Quaterniond turn = Eigen::Quaterniond(u(random), u(random), u(random), u(random)).normalized();
        Eigen::Matrix3d stretch = Eigen::Matrix3d::Identity();
        for (int i = 0; i < 3; ++i)
            for (int j = 0; j < 3; ++j) stretch(i, j) += 0.3 * u(random); // stretch and shear, det > 0 here
        if (stretch.determinant() <= 0.1) continue;
        const Eigen::Matrix3d a = turn.toRotationMatrix() * stretch;
        const Eigen::Matrix3d expected = polar(a);
        for (const Eigen::Quaterniond& start :
             {Eigen::Quaterniond::Identity(), Eigen::Quaterniond(Eigen::AngleAxisd(0.05, Eigen::Vector3d::UnitZ())) * Eigen::Quaterniond(expected),
              Eigen::Quaterniond(Eigen::AngleAxisd(2.5, Eigen::Vector3d(1, 1, 0).normalized())) * Eigen::Quaterniond(expected)}) {
            Eigen::Quaterniond q = start;
            extract_rotation(a, q);
            EXPECT_LT((q.toRotationMatrix() - expected).norm(), 1e-10) << "trial " << trial;
        }
    }
}

TEST(Corotation, AnInvertedElementGivesAProperRotation)
{
    const Eigen::Matrix3d a = Eigen::Vector3d(1.2, 0.9, -0.3).asDiagonal(); // flattened through itself
    Eigen::Quaterniond q = Eigen::Quaterniond::Identity();
    extract_rotation(a, q);
    const Eigen::Matrix3d r = q.toRotationMatrix();
    EXPECT_NEAR(r.determinant(), 1.0, 1e-12);
    // The best proper rotation for a diagonal A with one negative entry keeps the two positive
    // axes (identity): tr = 1.2 + 0.9 - 0.3 = 1.8, against 1.2 - 0.9 + 0.3 = 0.6 or less otherwise.
    EXPECT_NEAR((r.transpose() * a).trace(), 1.8, 1e-9);
}

TEST(Corotation, FourElementsAtOnceGetEachTheirOwnRotation)
{
    // Four gradients that need different numbers of iterations (one already at its rotation, one
    // far from its start, one inverted) and one not finite, whose start is kept: each lane ends
    // where the one-element extraction ends.
    std::mt19937 random(5);
    std::uniform_real_distribution<double> u(-1.0, 1.0);
    for (int trial = 0; trial < 50; ++trial) {
        std::array<Eigen::Matrix3d, 4> a;
        std::array<Eigen::Quaterniond, 4> start;
        for (std::size_t l = 0; l < 4; ++l) {
            const Eigen::Quaterniond turn = Eigen::Quaterniond(u(random), u(random), u(random), u(random)).normalized();
            Eigen::Matrix3d stretch = Eigen::Matrix3d::Identity();
            for (int i = 0; i < 3; ++i)
                for (int j = 0; j < 3; ++j) stretch(i, j) += 0.3 * u(random);
            a[l] = turn.toRotationMatrix() * stretch;
            start[l] = l == 0 ? turn : Eigen::Quaterniond(u(random), u(random), u(random), u(random)).normalized();
        }
        a[1] = Eigen::Vector3d(1.2, 0.9, -0.3).asDiagonal(); // inverted
        if (trial % 2) a[3](1, 2) = std::numeric_limits<double>::quiet_NaN();
        const int count = 2 + trial % 3; // 2, 3 or 4 lanes in use
        std::array<Eigen::Quaterniond, 4> one = start, four = start;
        for (int l = 0; l < count; ++l) extract_rotation(a[static_cast<std::size_t>(l)], one[static_cast<std::size_t>(l)]);
        const Eigen::Matrix3d* from[4] = {&a[0], &a[1], &a[2], &a[3]};
        Eigen::Quaterniond* to[4] = {&four[0], &four[1], &four[2], &four[3]};
        extract_rotations(from, to, count);
        for (std::size_t l = 0; l < 4; ++l) {
            if (l == 3 && trial % 2 && count == 4) {
                EXPECT_EQ(four[l].coeffs(), start[l].coeffs()) << "a gradient that is not finite keeps its start";
                continue;
            }
            if (static_cast<int>(l) >= count) {
                EXPECT_EQ(four[l].coeffs(), start[l].coeffs()) << "a lane not in use is left alone";
                continue;
            }
            EXPECT_LT((four[l].toRotationMatrix() - one[l].toRotationMatrix()).norm(), 1e-12) << "trial " << trial << ", lane " << l;
        }
    }
}
