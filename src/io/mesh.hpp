#pragma once
// Triangle meshes read from surface files (OFF, OBJ, PLY, STL) in world millimetres, and a summary
// of their topology and geometry (closed or open, orientation, area, enclosed volume).

#include <Eigen/Core>

#include <cstddef>
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

/// Reads a surface mesh, choosing the format by the file's extension (case-insensitive): .off and
/// .stl (ascii or binary) by our own parsers, .obj and .ply through OpenMesh. Polygons are
/// fan-triangulated; faces that repeat a vertex (zero area) are skipped with a warning. Coordinates
/// are multiplied by `mm_per_unit` to give world millimetres.
/// Throws InputError "PATH: problem" when the file is missing or unreadable, has an unknown
/// extension, is malformed or truncated, has no faces, a face references a missing vertex, or a
/// vertex has a NaN or infinite coordinate; also when `mm_per_unit` is not positive and finite.
[[nodiscard]] TriangleMesh read_mesh(const std::string& path, double mm_per_unit = 1.0);

/// Throws InputError "NAME: problem" unless the mesh has at least one triangle, every index is a
/// valid vertex index and every vertex is finite. `name` names the mesh (usually its file).
void check_mesh(const TriangleMesh& mesh, const std::string& name);

/// Topology and geometry of a triangle mesh. An edge is an unordered vertex pair used by at least
/// one triangle; lengths in mm, areas in mm^2, volumes in mm^3 (world frame).
struct MeshInfo {
    std::size_t vertices = 0;
    std::size_t triangles = 0;
    std::size_t edges = 0;
    std::size_t boundary_edges = 0;     ///< edges in exactly one triangle
    std::size_t non_manifold_edges = 0; ///< edges in more than two triangles
    std::size_t boundary_loops = 0;     ///< connected components of the boundary edges (holes)
    bool closed = false;                ///< every edge in exactly two triangles
    /// Every edge shared by several triangles is traversed as often in one direction as in the
    /// other, i.e. neighbouring triangles agree on which side is outside.
    bool consistently_oriented = false;
    double area_mm2 = 0.0;
    /// Signed volume by the divergence theorem, (1/6) sum over triangles of a . (b x c), with the
    /// corners taken relative to the bounding-box centre: positive for a closed mesh oriented
    /// outwards, negative when oriented inwards. For an open mesh it is only indicative.
    double enclosed_volume_mm3 = 0.0;
    /// Sum over boundary loops of the norm of the loop's vector area 0.5 * sum p_i x p_(i+1): the
    /// area of the flat caps that would close the holes. A fraction of `area_mm2` for a scan with
    /// holes (lion.off: 0.22, mostly its open base), comparable to it for a sheet that encloses
    /// nothing (the half-pipe cylinder.off: 0.64). Independent of the origin for closed loops.
    double boundary_cap_area_mm2 = 0.0;
    Eigen::Vector3d bbox_min = Eigen::Vector3d::Zero(); ///< of the vertices used by triangles
    Eigen::Vector3d bbox_max = Eigen::Vector3d::Zero();
};

/// Summarises a mesh whose indices are valid (see check_mesh). Runs in O(T log T) for T triangles.
[[nodiscard]] MeshInfo mesh_info(const TriangleMesh& mesh);

} // namespace vox::io
