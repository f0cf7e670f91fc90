#pragma once
// Stiffness and mass of a coarse element from its fine voxels (Jerabkova et al. 2010, section 2.2),
// three ways that must agree:
// - direct (the paper's n -> 1): the cell's voxels in Morton order; each maximal full octree
//   sub-node of level l (a Morton interval of 8^l codes, one material) adds
//   H^T (2^l K_0) H and H^T (2^3l M_0) H in one step (equations 2 to 4);
// - recursive (8 -> 1, Nesme et al. 2006): every non-empty octree node adds its matrices to its
//   parent, level by level (equation 1);
// - brute force: every fine voxel adds H^T K_0 H directly.
// Step counts follow the paper (its 2-D example: 10 direct, 49 + 14 + 4 = 67 recursive).
// Multi-material cells: a sub-node merges voxels of one material only, so all three stay exact.

#include "core/eigen_types.hpp"
#include "grid/elastic_material.hpp"

#include <cstdint>
#include <span>
#include <vector>

namespace vox::grid {

/// A fine voxel of a cell: Morton code of its local index (0 .. 2^L - 1 per axis) and its
/// material (index into the material table).
struct CellVoxel {
    std::uint64_t morton = 0;
    std::int32_t material = 0;
    friend bool operator<(const CellVoxel& a, const CellVoxel& b) { return a.morton < b.morton; }
};

/// A full octree sub-node: codes [first, first + 8^level), all one material.
struct SubNode {
    std::uint64_t first = 0;
    int level = 0;
    std::int32_t material = 0;
};

/// The maximal full sub-nodes of `voxels` (sorted by Morton code, unique), in Morton order,
/// found by one pass over the codes: a run is a sub-node of level l when it starts at a multiple
/// of 8^l and holds 8^l consecutive codes of one material. `dimensions` 2 gives the quadtree
/// version (4^l codes per node) of the paper's Figure 6.
[[nodiscard]] std::vector<SubNode> full_subnodes(std::span<const CellVoxel> voxels, int cell_level,
                                                 int dimensions = 3);

/// Interpolation from the corners of the sub-box at local voxel offset `origin` with edge `size`
/// (voxels) to the corners of a cell of edge `cell_size` voxels: H(a, b) = N_b(corner a of the
/// sub-box), 8 x 8 scalar (times the 3 x 3 identity per axis for displacements).
[[nodiscard]] Matrix8d subnode_interpolation(const Eigen::Vector3i& origin, int size, int cell_size);

struct CondensedElement {
    Matrix24d stiffness = Matrix24d::Zero(); ///< N/m
    Matrix8d mass = Matrix8d::Zero();        ///< kg, scalar (times I3 per axis)
    std::uint64_t steps = 0;                 ///< condensation steps, counted as the paper does
};

/// The three methods; `voxels` sorted by Morton code and unique; `cell_level` L in 0..6;
/// `voxel_size_m` the fine voxel's edges (anisotropic allowed).
[[nodiscard]] CondensedElement condense_direct(std::span<const CellVoxel> voxels, int cell_level,
                                               const Eigen::Vector3d& voxel_size_m,
                                               std::span<const ElasticMaterial> materials);
[[nodiscard]] CondensedElement condense_recursive(std::span<const CellVoxel> voxels, int cell_level,
                                                  const Eigen::Vector3d& voxel_size_m,
                                                  std::span<const ElasticMaterial> materials);
[[nodiscard]] CondensedElement condense_brute_force(std::span<const CellVoxel> voxels, int cell_level,
                                                    const Eigen::Vector3d& voxel_size_m,
                                                    std::span<const ElasticMaterial> materials);

/// Number of recursive condensation steps without computing matrices: the non-empty octree
/// (dimensions 3) or quadtree (2) nodes of levels 0 .. L-1.
[[nodiscard]] std::uint64_t recursive_step_count(std::span<const CellVoxel> voxels, int cell_level,
                                                 int dimensions = 3);

} // namespace vox::grid
