#pragma once
// A summary of a triangle mesh's topology and geometry: closed or open, orientation, area,
// enclosed volume, holes.

#include "io/mesh.hpp"

#include <Eigen/Core>

#include <cstddef>

namespace vox::io {

/// Topology and geometry of a triangle mesh. An edge is an unordered vertex pair used by at least
/// one triangle; lengths in mm, areas in mm^2, volumes in mm^3 (world frame).
struct MeshInfo {
    std::size_t vertices = 0;
    std::size_t triangles = 0;
    std::size_t edges = 0;
    std::size_t boundary_edges = 0;     ///< edges in exactly one triangle
    std::size_t non_manifold_edges = 0; ///< edges in more than two triangles
    std::size_t boundary_loops = 0;     ///< connected components of the boundary edges (holes)
    std::size_t components = 0;         ///< connected pieces: triangles joined through shared vertices
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
