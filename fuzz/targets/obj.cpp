// Fuzz target: OBJ meshes, read, described and voxelised (fuzz/mesh_target.hpp).
#include "mesh_target.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size)
{
    return vox::fuzz::read_mesh_input(data, size, "in.obj");
}
