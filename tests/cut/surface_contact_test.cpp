// How a contact at a surface vertex is shared by its element's corners: the force by the
// trilinear weights, the stiffness by weights that keep it positive semidefinite also for a
// vertex a little outside its element's cell (where marching cubes may put it), checked against
// the exact rank-one term w w^T of a penalty at the interpolated point.

#include "cut/surface_contact.hpp"

#include <gtest/gtest.h>

#include <Eigen/Eigenvalues>

namespace {
/// Smallest eigenvalue of diag(stiffness weights) - w w^T: the lumped stiffness less the exact one.
double excess(const vox::cut::VertexWeights& v)
{
    Eigen::Matrix<double, 8, 1> w;
    Eigen::Matrix<double, 8, 8> d = Eigen::Matrix<double, 8, 8>::Zero();
    for (int c = 0; c < 8; ++c) {
        w[c] = v.force[static_cast<std::size_t>(c)];
        d(c, c) = v.stiffness[static_cast<std::size_t>(c)];
    }
    return Eigen::SelfAdjointEigenSolver<Eigen::Matrix<double, 8, 8>>(d - w * w.transpose()).eigenvalues()[0];
}
} // namespace

TEST(SurfaceContact, InsideItsCellAVertexLumpsItsStiffnessByItsTrilinearWeights)
{
    const vox::cut::VertexWeights v = vox::cut::vertex_weights({0.3, 0.8, 0.55});
    double sum = 0.0;
    for (std::size_t c = 0; c < 8; ++c) {
        EXPECT_GE(v.force[c], 0.0);
        EXPECT_NEAR(v.stiffness[c], v.force[c], 1e-15); // |w| sum |w| = w: the row sums of w w^T
        sum += v.force[c];
    }
    EXPECT_NEAR(sum, 1.0, 1e-15);
    EXPECT_GE(excess(v), -1e-15);
}

TEST(SurfaceContact, OutsideItsCellTheLumpedStiffnessStaysPositiveAndBoundsTheExactOne)
{
    // Half a voxel of a level-4 cell (1/32) below it, as on the brain pressed at level 4: the
    // trilinear weights of the far corners turn negative, and lumped by them the stiffness did.
    for (const Eigen::Vector3d local : {Eigen::Vector3d(0.48, 0.24, -0.011), Eigen::Vector3d(-0.03, 1.03, 0.5), Eigen::Vector3d(1.02, -0.02, -0.02)}) {
        const vox::cut::VertexWeights v = vox::cut::vertex_weights(local);
        double sum = 0.0, negative = 0.0;
        for (std::size_t c = 0; c < 8; ++c) {
            EXPECT_GE(v.stiffness[c], 0.0) << local.transpose();
            sum += v.force[c];
            negative = std::min(negative, v.force[c]);
        }
        EXPECT_LT(negative, 0.0) << "the case this is about";
        EXPECT_NEAR(sum, 1.0, 1e-14) << "the force is shared exactly";
        EXPECT_GE(excess(v), -1e-14) << "positive semidefinite and at least the exact stiffness";
    }
}
