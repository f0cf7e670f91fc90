#pragma once
// The tetrahedral mesh of one level of the branched grid: each element (a hexahedron with its own
// eight nodes; superimposed elements of one cell have their own) split into the six tetrahedra
// around its cell's main diagonal, so disconnected material stays disconnected and the nodes are
// the hexahedral model's, held and loaded the same way. Partly filled elements: each tetrahedron
// carries the material of the fine voxels whose centres it holds, its stiffness and density
// scaled by its fill (a floor of 1e-3 keeps empty ones from leaving nodes without mass or
// stiffness, as the hexahedral model does).

#include "isxfem/xfem_model.hpp"

#include "fem/hex_model.hpp"

namespace vox::isxfem {

struct GridTets {
    TetMesh mesh;                          ///< nodes: the model's rest positions, world m
    std::vector<grid::ElasticMaterial> materials;    ///< one per tetrahedron
    std::vector<std::uint32_t> material;   ///< per tetrahedron: its index in `materials`
    std::vector<double> fill;              ///< per tetrahedron: share of its volume holding material
    /// Tetrahedra 6 e .. 6 e + 5 split model element e.
    [[nodiscard]] static std::size_t first_tet(std::size_t element) { return 6 * element; }
};

GridTets tets_from_model(const grid::BranchedGrid& grid, const fem::HexModel& model);

/// The tetrahedron of model element `element` that holds the rest point `x` (world m), and the
/// point's barycentric coordinates there (clamped to the tetrahedron when it lies on it to a
/// rounding error; a point outside the element gets those of the tetrahedron it is least outside).
std::pair<std::size_t, std::array<double, 4>> locate(const TetMesh& mesh, std::size_t element, const Eigen::Vector3d& x);

} // namespace vox::isxfem
