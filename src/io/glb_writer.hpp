#pragma once
// A labelled surface as glTF 2.0 binary (.glb), the format web viewers, Blender and 3D printing
// services open: one primitive per label with its colour, in metres, with glTF's +Y up. Our LPS
// millimetres map as glTF +X = LPS +x, +Y = LPS +z (superior), +Z = LPS -y (anterior), a
// rotation, so windings and handedness are kept; phantoms and meshes map the same way.

#include <Eigen/Core>

#include <cstdint>
#include <filesystem>
#include <functional>
#include <string>
#include <vector>

namespace vox::io {

/// Writes the triangles (each taking the label most of its corners have) of a surface in world
/// mm to `path` atomically, coloured by `color_of(label)` (RGB 0..1) and named by `name_of(label)`.
/// Throws InputError naming the path when it does not end in .glb or there is no triangle.
void write_glb(const std::filesystem::path& path, const std::vector<Eigen::Vector3d>& positions_mm,
               const std::vector<Eigen::Vector3i>& triangles, const std::vector<std::int32_t>& labels,
               const std::function<Eigen::Vector3d(std::int32_t)>& color_of,
               const std::function<std::string(std::int32_t)>& name_of);

} // namespace vox::io
