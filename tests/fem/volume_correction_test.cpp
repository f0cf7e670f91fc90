// The volume correction (fem/volume_correction.hpp): nothing where the linear model holds, a
// gradient that is the derivative of its energy (finite differences, the rotation taken anew at
// each), a force that turns a flattened or inverted element back out, and a positive Hessian part.

#include "fem/corotation.hpp"
#include "fem/volume_correction.hpp"

#include <gtest/gtest.h>

#include <Eigen/Geometry>

namespace vox::fem {
namespace {

Eigen::Matrix3d rotation_of(const Eigen::Matrix3d& f)
{
    Eigen::Quaterniond q = Eigen::Quaterniond::Identity();
    extract_rotation(f, q);
    return q.toRotationMatrix();
}

double energy(const Eigen::Matrix3d& f) { return volume_correction(f, rotation_of(f), 1.0).energy; }

TEST(VolumeCorrection, NothingAtRestInTensionOrUnderAMildSqueeze)
{
    const Eigen::Matrix3d turn = Eigen::AngleAxisd(0.7, Eigen::Vector3d(1, 2, 3).normalized()).toRotationMatrix();
    for (const Eigen::Matrix3d& f : {Eigen::Matrix3d(Eigen::Matrix3d::Identity()), Eigen::Matrix3d(turn * Eigen::Vector3d(1.3, 0.9, 1.0).asDiagonal()),
                                     Eigen::Matrix3d(turn * Eigen::Vector3d(0.985, 1.0, 1.0).asDiagonal())}) {
        const VolumeCorrection c = volume_correction(f, rotation_of(f), 2.0);
        EXPECT_EQ(c.energy, 0.0);
        EXPECT_EQ(c.gradient.norm(), 0.0);
        EXPECT_EQ(c.hessian.q.norm(), 0.0);
    }
}

TEST(VolumeCorrection, ItsGradientIsTheDerivativeOfItsEnergy)
{
    // Flattened to 0.6 with some shear and a turn (J = 0.6 x 1.05 x 1.02), in the blend (J = 0.95),
    // and past the clamp (J = 0.05).
    const Eigen::Matrix3d turn = Eigen::AngleAxisd(0.4, Eigen::Vector3d(-1, 2, 0.5).normalized()).toRotationMatrix();
    Eigen::Matrix3d shear = Eigen::Matrix3d::Identity();
    shear(0, 2) = 0.2;
    for (const Eigen::Vector3d& stretch : {Eigen::Vector3d(1.05, 1.02, 0.6), Eigen::Vector3d(1.0, 1.0, 0.95), Eigen::Vector3d(1.0, 1.0, 0.05)}) {
        const Eigen::Matrix3d f = turn * stretch.asDiagonal() * shear;
        const Eigen::Matrix3d g = volume_correction(f, rotation_of(f), 1.0).gradient;
        const double h = 1e-6;
        for (int i = 0; i < 3; ++i)
            for (int j = 0; j < 3; ++j) {
                Eigen::Matrix3d up = f, down = f;
                up(i, j) += h;
                down(i, j) -= h;
                EXPECT_NEAR(g(i, j), (energy(up) - energy(down)) / (2 * h), 1e-6 * (1.0 + g.norm())) << stretch.transpose() << " " << i << j;
            }
    }
}

TEST(VolumeCorrection, AFlattenedOrInvertedElementIsPushedBackOutWithAFiniteForce)
{
    for (const double height : {0.2, 0.01, -0.3}) {
        const Eigen::Matrix3d f = Eigen::Vector3d(1.0, 1.0, height).asDiagonal();
        const VolumeCorrection c = volume_correction(f, rotation_of(f), 1.0);
        EXPECT_TRUE(std::isfinite(c.energy) && c.gradient.allFinite()) << height;
        // Moving against the gradient (as the force does) thickens the element.
        EXPECT_LT(c.gradient(2, 2), 0.0) << height;
        const Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d> eigen(c.hessian.q);
        EXPECT_GE(eigen.eigenvalues().minCoeff(), -1e-12) << height;
        EXPECT_GT(eigen.eigenvalues().maxCoeff(), 0.0) << height;
    }
    // The flatter, the harder it pushes back.
    auto push = [](double height) {
        const Eigen::Matrix3d f = Eigen::Vector3d(1.0, 1.0, height).asDiagonal();
        return -volume_correction(f, rotation_of(f), 1.0).gradient(2, 2);
    };
    EXPECT_GT(push(0.3), push(0.6));
    EXPECT_GT(push(0.0), push(0.3));
}

} // namespace
} // namespace vox::fem
