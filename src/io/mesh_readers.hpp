#pragma once
// Internal to src/io: the per-format mesh readers that read_mesh dispatches to, and what they
// share (fan triangulation, point text; word splitting and number parsing are in
// io/text_parsing.hpp). Each reader returns vertices in file units; read_mesh scales them to
// millimetres and checks the result with check_mesh.

#include "io/mesh.hpp"

#include <Eigen/Core>

#include <cstddef>
#include <string>
#include <vector>

namespace vox::io::detail {

/// OFF, parsed by ourselves (off_reader.cpp). Throws InputError "PATH: problem" when the file is
/// missing, malformed or truncated.
[[nodiscard]] TriangleMesh read_off(const std::string& path);

/// STL, ascii or binary, parsed by ourselves (stl_reader.cpp); vertices shared between triangles
/// are welded by exact position. Throws InputError "PATH: problem" when the file is missing,
/// malformed or truncated, or a corner has a non-finite coordinate.
[[nodiscard]] TriangleMesh read_stl(const std::string& path);

/// Wavefront OBJ, parsed by ourselves (obj_reader.cpp): "v" and "f" records (corners i, i/j, i//k,
/// i/j/k, negative indices counting back), other records ignored. Throws InputError "PATH: line N:
/// problem" for a non-finite or malformed vertex, a bad index or a face with fewer than 3 corners,
/// and "PATH: problem" when the file is missing, empty, binary or has no faces.
[[nodiscard]] TriangleMesh read_obj(const std::string& path);

/// PLY, ascii or binary (either byte order), parsed by ourselves (ply_reader.cpp): x, y, z of
/// element vertex, the vertex_indices list of element face, everything else read past. Throws
/// InputError "PATH: problem" when the file is missing or empty, the header is malformed, the data
/// is truncated or longer than declared, a coordinate is not finite, an index is out of range, a
/// face has fewer than 3 corners, or there is no face.
[[nodiscard]] TriangleMesh read_ply(const std::string& path);

/// The most corners one face may have. Scanners and modellers write triangles and quads; a face of
/// thousands of corners is a corrupt file, and its fan of overlapping triangles would make
/// voxelising it take minutes.
inline constexpr std::size_t k_max_face_corners = 256;
/// "face of N corners, more than the 256 a face may have", for the readers' messages.
[[nodiscard]] std::string too_many_corners(double corners);

/// Accumulates polygons as triangle fans, skipping triangles that repeat a vertex (zero area).
struct MeshBuilder {
    TriangleMesh mesh;
    std::size_t skipped_faces = 0;

    /// Adds the fan (c0, c_i, c_i+1) of the polygon's corners, indices into mesh.vertices.
    void add_polygon(const std::vector<int>& corners);
    /// The mesh, after a warning naming `path` when faces were skipped.
    [[nodiscard]] TriangleMesh finish(const std::string& path);
};

/// "(x, y, z)", for messages about a point.
[[nodiscard]] std::string format_point(const Eigen::Vector3d& p);

} // namespace vox::io::detail
