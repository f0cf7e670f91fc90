// Fuzz target: OFF meshes: read, described (as `voxsculpt info`) and voxelised at 16 voxels across,
// so the voxeliser meets what the reader lets through without each input taking seconds.
#include "fuzz_input.hpp"

#include "io/mesh.hpp"
#include "io/mesh_info.hpp"
#include "io/mesh_voxelizer.hpp"

#include <cmath>

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size)
{
    return vox::fuzz::read_or_refuse([&] {
        const vox::io::TriangleMesh mesh = vox::io::read_mesh(vox::fuzz::input_file(data, size, "in.off"));
        const vox::io::MeshInfo info = vox::io::mesh_info(mesh);
        const double voxel_mm = (info.bbox_max - info.bbox_min).maxCoeff() / 16.0;
        if (std::isfinite(voxel_mm) && voxel_mm > 0.0) (void)vox::io::voxelize_mesh(mesh, voxel_mm, {});
    });
}
