#include "grid/phantom.hpp"

#include "core/error.hpp"

#include <gtest/gtest.h>

#include <cmath>

using namespace vox::grid;

TEST(Phantom, BeamHasExactVoxelsAndFirstCentreAtOrigin)
{
    PhantomSpec s = default_phantom(PhantomShape::beam);
    s.voxel_mm = 2.0;
    const LabelGrid g = make_phantom(s);
    EXPECT_EQ(g.active_voxel_count(), 100u * 5u * 5u);
    const IndexBox b = g.index_bounds();
    EXPECT_EQ(b.min, Coord(0, 0, 0));
    EXPECT_EQ(b.max, Coord(99, 4, 4));
    EXPECT_TRUE(g.index_to_world(Eigen::Vector3d::Zero()).isZero());
    EXPECT_TRUE(g.index_to_world(Eigen::Vector3d(99, 4, 4)).isApprox(Eigen::Vector3d(198, 8, 8)));
}

TEST(Phantom, SphereCountMatchesLatticePointCountAndVolume)
{
    PhantomSpec s = default_phantom(PhantomShape::sphere);
    s.radius_mm = 8.0;
    s.voxel_mm = 0.5;
    const LabelGrid g = make_phantom(s);
    // Independent count: lattice points (half-integer offsets from the centre) inside the ball.
    std::uint64_t expect = 0;
    const int n = 32;
    for (int i = 0; i < n; ++i)
        for (int j = 0; j < n; ++j)
            for (int k = 0; k < n; ++k) {
                const double x = (i + 0.5 - n / 2.0) * 0.5, y = (j + 0.5 - n / 2.0) * 0.5, z = (k + 0.5 - n / 2.0) * 0.5;
                if (x * x + y * y + z * z <= 64.0) ++expect;
            }
    EXPECT_EQ(g.active_voxel_count(), expect);
    // The voxel volume approaches the ball's: within 2% at 16 voxels per radius.
    const double volume = static_cast<double>(g.active_voxel_count()) * 0.125;
    EXPECT_NEAR(volume / (4.0 / 3.0 * M_PI * 512.0), 1.0, 0.02);
}

TEST(Phantom, CylinderIsADiscExtruded)
{
    PhantomSpec s = default_phantom(PhantomShape::cylinder);
    const LabelGrid g = make_phantom(s);
    std::uint64_t disc = 0;
    for (int j = 0; j < 10; ++j)
        for (int k = 0; k < 10; ++k)
            if ((j - 4.5) * (j - 4.5) + (k - 4.5) * (k - 4.5) <= 25.0) ++disc;
    EXPECT_EQ(g.active_voxel_count(), 60u * disc);
}

TEST(Phantom, UtubeIsBasePlusTwoLegs)
{
    const LabelGrid g = make_phantom(default_phantom(PhantomShape::utube));
    // 8 wide, 3 deep, 16 high; base 3 voxels thick over the full width, legs 3 wide above it.
    EXPECT_EQ(g.active_voxel_count(), 8u * 3u * 3u + 2u * 3u * 3u * 13u);
    EXPECT_EQ(g.get({3, 1, 10}), 0);  // the gap
    EXPECT_EQ(g.get({3, 1, 1}), 1);   // the base under the gap
    EXPECT_EQ(g.get({7, 2, 15}), 1);  // top of the right leg
}

TEST(Phantom, RefusesSizesThatAreNotWholeVoxels)
{
    PhantomSpec s = default_phantom(PhantomShape::block);
    s.voxel_mm = 3.0; // 20 mm is not a whole number of 3 mm voxels
    EXPECT_THROW((void)make_phantom(s), vox::InputError);
    s.voxel_mm = -1.0;
    EXPECT_THROW((void)make_phantom(s), vox::InputError);
    EXPECT_THROW((void)parse_phantom_shape("torus"), vox::InputError);
}
