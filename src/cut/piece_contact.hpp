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

#include <cstdint>
#include <vector>

namespace vox::cut {

struct PieceContact {
    contact::SurfacePatch patch;                ///< the surface tested
    std::vector<std::uint32_t> slots;           ///< surface vertex slot of each patch vertex
    std::vector<contact::FaceContact> faces;    ///< indices into the patch
    std::vector<contact::EdgeContact> edges;    ///< indices into the patch
    std::vector<fem::PairContact> pairs;        ///< the same on the model's nodes (N, N/m)
    std::size_t element_pairs = 0;              ///< element pairs the broad phase kept
};

/// `f` as a pair contact on a model's dof blocks: the vertex's point minus the pressed point
/// (its triangle's corners by their weights). `add(i, weight, terms)` adds patch vertex i's point
/// times weight to terms (a method's weights of a surface point on its blocks). It waits
/// (fem::PairContact::waiting) when apart by more than `skin_mm` at the start.
template <class AddPoint>
[[nodiscard]] fem::PairContact face_pair(const contact::FaceContact& f, const contact::SurfacePatch& patch, double skin_mm, AddPoint&& add)
{
    fem::PairContact pair;
    add(f.vertex, 1.0, pair.terms);
    for (std::size_t c = 0; c < 3; ++c)
        add(static_cast<std::uint32_t>(patch.triangles[f.triangle][static_cast<int>(c)]), -f.weights[c], pair.terms);
    pair.normal = f.normal;
    pair.force_n = f.force_n;
    pair.stiffness_n_per_m = 1e3 * f.stiffness_n_per_mm;
    pair.waiting = f.depth_mm < -skin_mm;
    return pair;
}

/// `e` as a pair contact, as face_pair: the pressing edge's point minus the pressed edge's.
template <class AddPoint>
[[nodiscard]] fem::PairContact edge_pair(const contact::EdgeContact& e, double skin_mm, AddPoint&& add)
{
    fem::PairContact pair;
    add(e.edge[0], 1.0 - e.s, pair.terms);
    add(e.edge[1], e.s, pair.terms);
    add(e.pressed[0], e.t - 1.0, pair.terms);
    add(e.pressed[1], -e.t, pair.terms);
    pair.normal = e.normal;
    pair.force_n = e.force_n;
    pair.stiffness_n_per_m = 1e3 * e.stiffness_n_per_mm;
    pair.waiting = e.depth_mm < -skin_mm;
    return pair;
}

/// Contact of the surface, deformed by `node_positions` (m) and predicted at `node_ends` (m) at
/// the step's end (fem::ImplicitSolver::free_step_positions), with itself. Two elements are
/// tested when their boxes, swept from start to end, come within `parameters.approach_mm` of
/// each other.
[[nodiscard]] PieceContact touch_pieces(const ModelSurface& surface, const std::vector<Eigen::Vector3d>& node_positions,
                                        const std::vector<Eigen::Vector3d>& node_ends, const contact::PieceContactParameters& parameters);

} // namespace vox::cut
