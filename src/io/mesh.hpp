#pragma once
// Triangle meshes read from surface files (OFF, OBJ, PLY, STL) in world millimetres. Their
// topology and geometry are summarised by mesh_info (io/mesh_info.hpp).

#include <Eigen/Core>

#include <string>
#include <vector>

namespace vox::io {

/// Triangles with shared vertices. `vertices` are positions in world mm; `triangles` hold three
/// indices into `vertices` each, counter-clockwise seen from outside when the surface is oriented
/// outwards. Open, non-manifold or self-intersecting surfaces are allowed (scans often are).
struct TriangleMesh {
    std::vector<Eigen::Vector3d> vertices;
    std::vector<Eigen::Vector3i> triangles;
};

/// Reads a surface mesh, choosing the format by the file's extension (case-insensitive): .off,
/// .obj, .ply (ascii or binary) and .stl (ascii or binary), all by our own parsers. Polygons are
/// fan-triangulated; faces that repeat a vertex (zero area) are skipped with a warning. Coordinates
/// are multiplied by `mm_per_unit` to give world millimetres.
/// Throws InputError "PATH: problem" when the file is missing or unreadable, has an unknown
/// extension, is empty, malformed or truncated, has no faces, a face references a missing vertex, or a
/// vertex has a NaN or infinite coordinate; also when `mm_per_unit` is not positive and finite.
[[nodiscard]] TriangleMesh read_mesh(const std::string& path, double mm_per_unit = 1.0);

/// Throws InputError "NAME: problem" unless the mesh has at least one triangle, every index is a
/// valid vertex index and every vertex is finite. `name` names the mesh (usually its file).
void check_mesh(const TriangleMesh& mesh, const std::string& name);

} // namespace vox::io
