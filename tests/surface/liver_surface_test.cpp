// The surface of the bundled liver (label 255): closed, outward, and its volume close to the voxels'.

#include "surface/embedded_surface.hpp"

#include "io/mesh_info.hpp"
#include "io/selection.hpp"
#include "io/volume_reader.hpp"

#include <gtest/gtest.h>

using namespace vox;

TEST(LiverSurface, ClosedOutwardAndVolumeWithinTheDocumentedBound)
{
    io::Selection selection;
    selection.labels = {255};
    const grid::LabelGrid labels = io::select_voxels(io::read_volume(VOX_SOURCE_DIR "/data/liver.inr.gz"), selection);
    const grid::BranchedGrid grid(grid::FineVoxels(labels, [](std::int32_t) { return 0; }),
                                  {{grid::lame_from_young_poisson(3e4, 0.45), 1060.0}}, 3);
    const surface::EmbeddedSurface s(grid, 3);
    EXPECT_GE(s.triangle_count(), 300000u);
    EXPECT_LE(s.triangle_count(), 450000u);

    const surface::SurfaceMesh m = s.mesh(grid);
    io::TriangleMesh t;
    t.vertices = m.positions;
    t.triangles = m.triangles;
    const io::MeshInfo info = io::mesh_info(t);
    EXPECT_TRUE(info.closed);
    EXPECT_TRUE(info.consistently_oriented);
    EXPECT_EQ(info.non_manifold_edges, 0u);

    // Documented bound (docs/surface.md): the two solids differ only inside surface cubes, so
    // |V_mc - V_voxels| <= (number of surface cubes) x voxel volume <= triangles x voxel volume.
    // Measured: marching cubes trims convex corners, so V_mc is slightly smaller.
    const double voxel_volume = grid.voxels().voxel_size_m().prod() * 1e9; // mm^3
    const double voxels = 3160496.0 * voxel_volume;
    EXPECT_GT(info.enclosed_volume_mm3, 0.0);
    EXPECT_LE(std::abs(info.enclosed_volume_mm3 - voxels), static_cast<double>(s.triangle_count()) * voxel_volume);
    EXPECT_LT(std::abs(info.enclosed_volume_mm3 / voxels - 1.0), 0.05);
    std::printf("liver surface: %zu triangles, %zu vertices, volume %.6g mm^3 (voxels %.6g mm^3, ratio %.5f)\n",
                s.triangle_count(), s.vertex_count(), info.enclosed_volume_mm3, voxels, info.enclosed_volume_mm3 / voxels);
}
