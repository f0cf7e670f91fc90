#pragma once
// Writing triangle meshes (world millimetres) as OBJ, PLY, STL or OFF, chosen by the extension.

#include <Eigen/Core>

#include <cstdint>
#include <span>
#include <string>

namespace vox::io {

/// Writes the mesh atomically (nothing is left behind on failure): .obj and .off as text with 9
/// significant digits; .ply binary little-endian, float32 coordinates plus an int32 `label` per
/// vertex when `labels` is not empty; .stl binary, float32, one normal per facet (unit, from the
/// winding). Throws InputError for an unknown extension or an unwritable path.
void write_mesh(const std::string& path, std::span<const Eigen::Vector3d> positions,
                std::span<const Eigen::Vector3i> triangles, std::span<const std::int32_t> labels = {});

/// True for the extensions write_mesh knows (.obj .ply .stl .off, any case).
[[nodiscard]] bool is_writable_mesh_path(const std::string& path);

} // namespace vox::io
