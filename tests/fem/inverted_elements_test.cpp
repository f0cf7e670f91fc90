// Inverted elements: none at rest, none under a rigid motion or a mirror-free squeeze; an element
// flattened through itself (a layer of nodes pushed past the opposite layer) counts, and only it.

#include "block_grid.hpp"
#include "fem/hex_model.hpp"

#include <Eigen/Geometry>
#include <gtest/gtest.h>

using namespace vox;

TEST(InvertedElements, NoneAtRestUnderARigidMotionOrASqueezeAndOneFlattenedThroughItself)
{
    // Four 1 mm cubes in a row along x (level 1 of a 4 x 1 x 1 mm block: one element a voxel here).
    const fem::HexModel model(test::block_grid({4, 1, 1}, 1), 0);
    ASSERT_EQ(model.elements().size(), 4u);
    std::vector<Eigen::Vector3d> x = model.rest_positions();
    EXPECT_EQ(fem::element_shapes(model, x).inverted, 0u);
    const Eigen::Matrix3d turn = Eigen::AngleAxisd(2.0, Eigen::Vector3d(1, 2, 3).normalized()).toRotationMatrix();
    for (Eigen::Vector3d& p : x) p = turn * p + Eigen::Vector3d(0.1, -0.2, 0.3);
    EXPECT_EQ(fem::element_shapes(model, x).inverted, 0u);
    x = model.rest_positions();
    for (Eigen::Vector3d& p : x) p.z() *= 0.05; // squeezed to a twentieth: thin, not inverted
    EXPECT_EQ(fem::element_shapes(model, x).inverted, 0u);
    // The last element (x from 2.5 to 3.5 mm) flattened through itself: its far face pushed back
    // past its near face.
    x = model.rest_positions();
    for (Eigen::Vector3d& p : x)
        if (std::abs(p.x() - 3.5e-3) < 1e-9) p.x() = 2.0e-3;
    EXPECT_EQ(fem::element_shapes(model, x).inverted, 1u);
}

TEST(ElementShapes, StretchIsOneAtRestAndTurnedAndGrowsWithTheElementOrIsInfiniteWhenNotFinite)
{
    const fem::HexModel model(test::block_grid({4, 1, 1}, 1), 0);
    std::vector<Eigen::Vector3d> x = model.rest_positions();
    EXPECT_DOUBLE_EQ(fem::element_shapes(model, x).max_stretch, 1.0);
    const Eigen::Matrix3d turn = Eigen::AngleAxisd(2.0, Eigen::Vector3d(1, 2, 3).normalized()).toRotationMatrix();
    for (Eigen::Vector3d& p : x) p = turn * p;
    EXPECT_NEAR(fem::element_shapes(model, x).max_stretch, 1.0, 1e-12);
    // The last element stretched along x to three times its length: F = diag(3, 1, 1), whose root
    // mean square stretch is sqrt(11 / 3); it is the one named, at its corners' mean.
    x = model.rest_positions();
    for (Eigen::Vector3d& p : x)
        if (std::abs(p.x() - 3.5e-3) < 1e-9) p.x() = 2.5e-3 + 3.0e-3;
    const fem::ElementShapes stretched = fem::element_shapes(model, x);
    EXPECT_NEAR(stretched.max_stretch, std::sqrt(11.0 / 3.0), 1e-12);
    EXPECT_NEAR(stretched.most_stretched_m.x(), 4.0e-3, 1e-12);
    EXPECT_EQ(stretched.inverted, 0u);
    x[0].x() = std::nan("");
    const fem::ElementShapes broken = fem::element_shapes(model, x);
    EXPECT_EQ(broken.max_stretch, INFINITY);
    EXPECT_EQ(broken.inverted, 1u);
}
