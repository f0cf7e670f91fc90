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
    EXPECT_EQ(fem::inverted_elements(model, x), 0u);
    const Eigen::Matrix3d turn = Eigen::AngleAxisd(2.0, Eigen::Vector3d(1, 2, 3).normalized()).toRotationMatrix();
    for (Eigen::Vector3d& p : x) p = turn * p + Eigen::Vector3d(0.1, -0.2, 0.3);
    EXPECT_EQ(fem::inverted_elements(model, x), 0u);
    x = model.rest_positions();
    for (Eigen::Vector3d& p : x) p.z() *= 0.05; // squeezed to a twentieth: thin, not inverted
    EXPECT_EQ(fem::inverted_elements(model, x), 0u);
    // The last element (x from 2.5 to 3.5 mm) flattened through itself: its far face pushed back
    // past its near face.
    x = model.rest_positions();
    for (Eigen::Vector3d& p : x)
        if (std::abs(p.x() - 3.5e-3) < 1e-9) p.x() = 2.0e-3;
    EXPECT_EQ(fem::inverted_elements(model, x), 1u);
}
