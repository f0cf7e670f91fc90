#include "grid/hex8.hpp"

#include <Eigen/Eigenvalues>
#include <gtest/gtest.h>

using namespace vox;
using namespace vox::grid;

namespace {
const Eigen::Vector3d k_size(0.002, 0.003, 0.005); // anisotropic, metres
const Lame k_material = lame_from_young_poisson(3e4, 0.45);

Eigen::Vector3d corner(int c, const Eigen::Vector3d& size)
{
    return {size.x() * (c & 1), size.y() * ((c >> 1) & 1), size.z() * ((c >> 2) & 1)};
}

/// Nodal displacements of the linear field u(x) = A x.
Vector24d linear_field(const Eigen::Matrix3d& a, const Eigen::Vector3d& size)
{
    Vector24d u;
    for (int c = 0; c < 8; ++c) u.segment<3>(3 * c) = a * corner(c, size);
    return u;
}
} // namespace

TEST(Hex8, StiffnessIsSymmetricWithRigidNullSpace)
{
    const Matrix24d k = hex8_stiffness(k_size, k_material);
    EXPECT_LT((k - k.transpose()).norm(), 1e-12 * k.norm());
    // Translations and infinitesimal rotations (skew A) produce no force.
    for (int axis = 0; axis < 3; ++axis) {
        Vector24d t = Vector24d::Zero();
        for (int c = 0; c < 8; ++c) t[3 * c + axis] = 1.0;
        EXPECT_LT((k * t).norm(), 1e-12 * k.norm());
        Eigen::Matrix3d skew = Eigen::Matrix3d::Zero();
        skew((axis + 1) % 3, (axis + 2) % 3) = 1.0;
        skew((axis + 2) % 3, (axis + 1) % 3) = -1.0;
        EXPECT_LT((k * linear_field(skew, k_size)).norm(), 1e-12 * k.norm() * k_size.norm());
    }
    Eigen::SelfAdjointEigenSolver<Matrix24d> eig(k);
    EXPECT_LT(std::abs(eig.eigenvalues()[5]), 1e-10 * eig.eigenvalues()[23]);
    EXPECT_GT(eig.eigenvalues()[6], 1e-6 * eig.eigenvalues()[23]); // exactly 6 zero modes
}

TEST(Hex8, LinearFieldsStoreTheAnalyticStrainEnergy)
{
    // For u = A x the strain is uniform, eps = (A + A^T) / 2, and the energy is
    // V (lambda tr(eps)^2 / 2 + mu eps : eps): trilinear elements reproduce it exactly.
    Eigen::Matrix3d a;
    a << 0.01, 0.002, -0.003, 0.004, -0.02, 0.001, 0.0, 0.005, 0.015;
    const Eigen::Matrix3d eps = 0.5 * (a + a.transpose());
    const double expect =
        k_size.prod() * (0.5 * k_material.lambda * eps.trace() * eps.trace() + k_material.mu * (eps.array() * eps.array()).sum());
    const Vector24d u = linear_field(a, k_size);
    EXPECT_NEAR(0.5 * u.dot(hex8_stiffness(k_size, k_material) * u), expect, 1e-12 * expect);
}

TEST(Hex8, ConsistentMassIsTheTensorProductOfOneDimensionalMasses)
{
    const double rho = 1060.0;
    const Matrix8d m = hex8_mass(k_size, rho);
    EXPECT_NEAR(m.sum(), rho * k_size.prod(), 1e-15);
    // 1-D consistent mass of a unit bar: [2 1; 1 2] / 6.
    for (int c = 0; c < 8; ++c)
        for (int d = 0; d < 8; ++d) {
            double expect = rho * k_size.prod();
            for (int axis = 0; axis < 3; ++axis) expect *= (((c >> axis) & 1) == ((d >> axis) & 1)) ? 2.0 / 6.0 : 1.0 / 6.0;
            EXPECT_NEAR(m(c, d), expect, 1e-15);
        }
}
