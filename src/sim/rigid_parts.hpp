#pragma once
// Where a scene's rigid material is, and what it does (io::Material::rigid): the elements that
// hold any rigid voxel are rigid; a piece of rigid elements alone that nothing holds moves as one
// rigid body (as does every unheld piece under "unheld_pieces": "rigid"); all other rigid
// elements are held in place, and with their nodes the soft material attached to them. Both
// methods ask here, so they agree on what is rigid.

#include "fem/hex_model.hpp"
#include "grid/branched_grid.hpp"
#include "io/scene.hpp"

#include <cstdint>
#include <vector>

namespace vox::sim {

/// Per grid material index (io::material_table's order): 1 when the scene makes it rigid.
[[nodiscard]] std::vector<unsigned char> rigid_materials(const io::Scene& scene);

/// Per element of `model` (a level of `grid`): 1 when any of its voxels is of a rigid material.
[[nodiscard]] std::vector<unsigned char> rigid_elements(const grid::BranchedGrid& grid, const fem::HexModel& model,
                                                        const std::vector<unsigned char>& rigid_material);

/// `constrained` (per node) with the nodes of rigid elements in pieces that also hold soft
/// material added: such a piece is held by its rigid material, as by a constraint.
[[nodiscard]] std::vector<unsigned char> anchoring_nodes(const fem::HexModel& model, const std::vector<unsigned char>& rigid_element,
                                                         std::vector<unsigned char> constrained);

struct RigidParts {
    std::vector<unsigned char> anchored;            ///< per node: held in place by rigid material
    std::vector<std::vector<std::uint32_t>> bodies; ///< the nodes of each piece moving as one rigid body
    std::size_t rigid_elements = 0;
};

/// `held`: per node, held by a constraint or by "unheld_pieces": "hold" (a piece with such a
/// node never moves as a body). `unheld_rigid`: every piece with no held node moves as a body,
/// whatever its material ("unheld_pieces": "rigid").
[[nodiscard]] RigidParts rigid_parts(const fem::HexModel& model, const std::vector<unsigned char>& rigid_element,
                                     const std::vector<unsigned char>& held, bool unheld_rigid);

} // namespace vox::sim
