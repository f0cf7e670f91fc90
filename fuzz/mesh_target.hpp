#pragma once
// What the four mesh targets share: the mesh read, described (as `voxsculpt info`) and voxelised
// at 16 voxels across, so the voxeliser meets what the reader lets through without each input
// taking seconds.

#include "fuzz_input.hpp"
#include "io/mesh.hpp"
#include "io/mesh_info.hpp"
#include "io/mesh_voxelizer.hpp"

#include <cmath>

namespace vox::fuzz {

/// The input as a mesh file named `name` (its extension picks the reader).
inline int read_mesh_input(const std::uint8_t* data, std::size_t size, const char* name)
{
    return read_or_refuse([&] {
        const io::TriangleMesh mesh = io::read_mesh(input_file(data, size, name));
        const io::MeshInfo info = io::mesh_info(mesh);
        const double voxel_mm = (info.bbox_max - info.bbox_min).maxCoeff() / 16.0;
        if (std::isfinite(voxel_mm) && voxel_mm > 0.0) (void)io::voxelize_mesh(mesh, voxel_mm, {});
    });
}

} // namespace vox::fuzz
