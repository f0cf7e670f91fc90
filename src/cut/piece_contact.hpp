#pragma once
// The branched grid's surface pressed against itself (contact/piece_contact.hpp): pieces on
// pieces, the walls of a cut, folds; each contact gathered on the model's nodes as a pair contact
// (fem/pair_contact.hpp) that couples the two sides.
//
// Broad phase, by elements: only elements holding surface vertices, and of those only pairs whose
// deformed boxes (swept over the step: the start and the predicted end) come within the contact's
// depth of each other but share no node. Elements that share a node are joined by material; an
// object left whole, at rest or bent gently, has no such pair and costs one pass over its surface
// elements. Pieces and walls that lie on each other (a cut, superimposed elements of one cell)
// do, and their vertices and the triangles around them are tested.

#include "contact/piece_contact.hpp"
#include "cut/model_surface.hpp"
#include "fem/pair_contact.hpp"

#include <vector>

namespace vox::cut {

struct PieceContact {
    contact::SurfacePatch patch;                ///< the surface tested
    std::vector<std::uint32_t> slots;           ///< surface vertex slot of each patch vertex
    std::vector<contact::FaceContact> faces;    ///< indices into the patch
    std::vector<fem::PairContact> pairs;        ///< the same on the model's nodes (N, N/m)
    std::size_t element_pairs = 0;              ///< element pairs the broad phase kept
};

/// Contact of the surface, deformed by `node_positions` (m) and predicted at `node_ends` (m) at
/// the step's end (fem::ImplicitSolver::free_step_positions), with itself. Two elements are
/// tested when their boxes, swept from start to end, come within `parameters.approach_mm` of
/// each other.
[[nodiscard]] PieceContact touch_pieces(const ModelSurface& surface, const std::vector<Eigen::Vector3d>& node_positions,
                                        const std::vector<Eigen::Vector3d>& node_ends, const contact::PieceContactParameters& parameters);

} // namespace vox::cut
