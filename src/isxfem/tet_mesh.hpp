#pragma once
// A tetrahedral mesh: rest positions and positively oriented tetrahedra.

#include <Eigen/Core>

#include <array>
#include <cstdint>
#include <vector>

namespace vox::isxfem {

struct TetMesh {
    std::vector<Eigen::Vector3d> nodes;                  ///< rest positions, world m
    std::vector<std::array<std::uint32_t, 4>> tets;      ///< node indices, positive volume
    [[nodiscard]] std::array<Eigen::Vector3d, 4> corners(std::size_t t) const
    {
        return {nodes[tets[t][0]], nodes[tets[t][1]], nodes[tets[t][2]], nodes[tets[t][3]]};
    }
};

/// A box of cells.x() x cells.y() x cells.z() cubes of edge h (m) from the origin, each split into
/// the six tetrahedra around its main diagonal (Kuhn's subdivision: neighbouring cubes split
/// their shared faces the same way, so the mesh is conforming).
TetMesh cube_lattice(const Eigen::Vector3i& cells, double h);

/// Signed volume of a tetrahedron, m^3.
double signed_volume(const std::array<Eigen::Vector3d, 4>& x);

/// Barycentric coordinates of `x` in tetrahedron `t` (negative ones outside it).
std::array<double, 4> barycentric(const TetMesh& mesh, std::size_t t, const Eigen::Vector3d& x);

/// The coordinates clamped to the tetrahedron (negative ones to zero, then normalised): for a
/// point a rounding error outside.
std::array<double, 4> clamped(std::array<double, 4> bary);

/// Per tetrahedron, the one across the face opposite each corner (-1: a boundary face). Faces are
/// matched by their nodes, so tetrahedra with their own nodes (superimposed elements) stay apart.
std::vector<std::array<std::int32_t, 4>> face_neighbours(const TetMesh& mesh);

/// The tetrahedron holding `x`, walking from `start` across the face `x` lies furthest beyond,
/// and the point's coordinates there (clamped). Where the walk leaves the mesh (or goes round
/// in circles) it stops in the last tetrahedron.
std::pair<std::size_t, std::array<double, 4>> walk_to(const TetMesh& mesh, const std::vector<std::array<std::int32_t, 4>>& neighbours,
                                                      std::size_t start, const Eigen::Vector3d& x);

} // namespace vox::isxfem
