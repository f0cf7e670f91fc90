// The element kernel (component-major corner vectors, rotations, the stiffness product, gathers
// and scatters) against Eigen's plain products of the same corner-major matrices: the same
// numbers to round-off, on random matrices (nothing in it may assume symmetry) and rotations.

#include "fem/element_kernel.hpp"

#include <gtest/gtest.h>

#include <Eigen/Geometry>

#include <random>

namespace vox::fem {
namespace {

TEST(ElementKernel, RotatedStiffnessProductEqualsEigensCornerMajorProduct)
{
    std::mt19937 rng(7);
    std::uniform_real_distribution<double> value(-1.0, 1.0);
    for (int trial = 0; trial < 20; ++trial) {
        Matrix24d k;
        for (int i = 0; i < 24; ++i)
            for (int j = 0; j < 24; ++j) k(i, j) = 1e5 * value(rng);
        const Eigen::Matrix3d r = Eigen::Quaterniond(Eigen::Vector4d(value(rng), value(rng), value(rng), value(rng)).normalized()).toRotationMatrix();
        // Eleven nodes, eight of them the corners, in a scrambled order.
        const std::array<std::uint32_t, 8> node{9, 2, 7, 0, 10, 4, 1, 5};
        Eigen::VectorXd p(33), out = Eigen::VectorXd::Zero(33);
        for (Eigen::Index i = 0; i < p.size(); ++i) p[i] = value(rng);

        // Corner c gets the sum over corners d of r K_cd r^T p_d.
        Vector24d gathered, expected = Vector24d::Zero();
        for (int c = 0; c < 8; ++c) gathered.segment<3>(3 * c) = p.segment<3>(3 * node[static_cast<std::size_t>(c)]);
        for (int c = 0; c < 8; ++c)
            for (int d = 0; d < 8; ++d)
                expected.segment<3>(3 * c) += r * (k.block<3, 3>(3 * c, 3 * d) * (r.transpose() * gathered.segment<3>(3 * d)));

        const Matrix24d kc = to_component_major(k);
        scatter_add(turn(r, stiffness_times(kc, turn(r, gather(p.data(), node), true)), false), out.data(), node);
        for (int c = 0; c < 8; ++c)
            EXPECT_LT((out.segment<3>(3 * node[static_cast<std::size_t>(c)]) - expected.segment<3>(3 * c)).norm(), 1e-12 * k.norm() * p.norm())
                << "trial " << trial << ", corner " << c;
        for (int n : {3, 6, 8}) EXPECT_EQ(out.segment<3>(3 * n).norm(), 0.0) << "node " << n << " is no corner";
        for (int c = 0; c < 8; ++c)
            for (int d = 0; d < 8; ++d) EXPECT_EQ(corner_block(kc, c, d), (k.block<3, 3>(3 * c, 3 * d)).eval());
        const CornerVectors u = from_corner_major(gathered);
        EXPECT_EQ(to_corner_major(u), gathered);
        EXPECT_NEAR(dot(u, u), gathered.squaredNorm(), 1e-14 * gathered.squaredNorm());
    }
}

} // namespace
} // namespace vox::fem
