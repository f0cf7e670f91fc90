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

} // namespace vox::isxfem
