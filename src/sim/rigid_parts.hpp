#pragma once
// Where a scene's rigid material is, and what it does (io::Material::rigid). In an element that
// holds rigid voxels, the corners nearest them are held: each rigid voxel holds the corner of the
// octant of its cell it lies in, so an element full of bone holds all eight corners, and one a
// bone surface crosses holds the bone side and leaves the soft side free (a thin scalp on a
// skull deforms at levels whose cells are thicker than it). A piece of rigid material alone that
// nothing holds moves as one rigid body instead (as does every unheld piece under
// "unheld_pieces": "rigid"). Both methods ask here, so they agree on what is rigid.

#include "fem/hex_model.hpp"
#include "grid/branched_grid.hpp"
#include "io/scene.hpp"

#include <cstdint>
#include <vector>

namespace vox::sim {

/// Per grid material index (io::material_table's order): 1 when the scene makes it rigid.
[[nodiscard]] std::vector<unsigned char> rigid_materials(const io::Scene& scene);

/// What an element of the model holds of rigid material.
struct RigidContent {
    std::uint8_t corners = 0; ///< bit c: a rigid voxel lies in the octant of corner c (0: no rigid voxel)
    bool soft = false;        ///< it also holds voxels of other materials
};

/// Per element of `model` (a level of `grid`).
[[nodiscard]] std::vector<RigidContent> rigid_content(const grid::BranchedGrid& grid, const fem::HexModel& model,
                                                      const std::vector<unsigned char>& rigid_material);

/// `constrained` (per node) with the held corners of rigid material added in pieces that also
/// hold soft material: such a piece is held by its rigid material, as by a constraint. `piece`:
/// each element's piece (cut::element_pieces).
[[nodiscard]] std::vector<unsigned char> anchoring_nodes(const fem::HexModel& model, const std::vector<std::uint32_t>& piece,
                                                         const std::vector<RigidContent>& rigid, std::vector<unsigned char> constrained);

struct RigidParts {
    std::vector<unsigned char> anchored;            ///< per node: held in place by rigid material
    std::vector<std::vector<std::uint32_t>> bodies; ///< the nodes of each piece moving as one rigid body
    std::size_t rigid_elements = 0;                 ///< elements holding rigid material
};

/// `held`: per node, held by a constraint or by "unheld_pieces": "hold" (a piece with such a
/// node never moves as a body). `unheld_rigid`: every piece with no held node moves as a body,
/// whatever its material ("unheld_pieces": "rigid").
[[nodiscard]] RigidParts rigid_parts(const fem::HexModel& model, const std::vector<std::uint32_t>& piece,
                                     const std::vector<RigidContent>& rigid, const std::vector<unsigned char>& held, bool unheld_rigid);

} // namespace vox::sim
