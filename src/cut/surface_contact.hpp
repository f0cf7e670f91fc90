#pragma once
// A tool pressed against the deformed surface: the contact module's penalty model evaluated on
// the surface vertices near the tool, and its forces gathered on the model's nodes (each vertex's
// force shared by the corners of its element with the trilinear weights; the penalty stiffness
// lumped the same way), ready for the solver's implicit contact.

#include "contact/obstacle.hpp"
#include "contact/penalty_contact.hpp"
#include "cut/model_surface.hpp"
#include "fem/implicit_solver.hpp"

#include <array>
#include <vector>

namespace vox::cut {

struct SurfaceContact {
    contact::ContactResult contact;         ///< its points index `vertices`
    std::vector<std::uint32_t> vertices;    ///< surface vertex slot of each contact point
    std::vector<std::uint64_t> keys;        ///< and that vertex's identity (SurfaceVertex::key)
    std::vector<fem::NodeContact> nodes;    ///< the forces on the model's nodes (N, N/m)
    /// An obstacle's push along its normal, one side's pair contact per point (taken at the
    /// step's end, let go if it would pull); `nodes` then holds only the friction.
    std::vector<fem::PairContact> pairs;
    std::vector<std::uint32_t> elements;    ///< model elements holding contact points (sorted, unique)
};

/// Contact of `tool` (its inner shape; the outer is grown by parameters.margin_mm) with the
/// surface deformed by `node_positions` (m). Only elements whose deformed corner box meets the
/// tool's reach are visited. With `from`, the tool's pose at the previous step, the penalty is
/// integrated over each point's penetration interval as the tool moved from there
/// (contact::penalty_contact).
[[nodiscard]] SurfaceContact touch_surface(const ModelSurface& surface, const std::vector<Eigen::Vector3d>& node_positions,
                                           const contact::PlacedShape& tool, const contact::ContactParameters& parameters,
                                           const contact::PlacedShape* from = nullptr);

/// Contact of the surface deformed by `node_positions` (m) and moving at `node_velocities` (m/s)
/// with a static obstacle for a step of `dt_s` (contact::obstacle_contact; `anchors` its
/// friction's, by surface vertex key; vertices nearer than `skin_mm`, or inside at the nodes'
/// free step's end `node_ends` (fem::ImplicitSolver::free_step_positions), are caught; those
/// apart wait: fem::PairContact::waiting): the push
/// along the obstacle's normal as one-sided pair contacts, the friction gathered on the nodes.
/// Only elements whose deformed corner box, swept over the step, may reach into the obstacle are
/// visited.
[[nodiscard]] SurfaceContact touch_obstacle(const ModelSurface& surface, const std::vector<Eigen::Vector3d>& node_positions,
                                            const std::vector<Eigen::Vector3d>& node_ends,
                                            const std::vector<Eigen::Vector3d>& node_velocities, double dt_s,
                                            const contact::Obstacle& obstacle, contact::FrictionAnchors& anchors, double skin_mm);

/// Adds `weight` times vertex slot v's trilinear weights on its element's nodes to `terms` (a
/// surface point as a pair contact's side: fem/pair_contact.hpp).
void add_vertex_terms(const ModelSurface& surface, std::uint32_t v, double weight, std::vector<fem::BlockWeight>& terms);

/// A surface vertex's trilinear weights on its element's corners, and the weights its stiffness is
/// lumped onto them by. Marching cubes may place a vertex up to half a voxel outside its element's
/// cell (between a voxel of the cell and one of the next), where some weights are slightly
/// negative. A force is shared by the weights (it acts at the vertex, exactly); a stiffness lumped
/// by them would be negative on those corners, and on a corner node little else holds it made the
/// step's matrix indefinite (a brain pressed by a probe at level 4: the warped Cholesky factor
/// failed at such a node 10 mm above the surface, CG stalled and the node ran off to 1.9 m). The
/// stiffness is lumped by |w_i| sum_j |w_j| instead: a diagonal that bounds the exact rank-one
/// term w w^T from above (diagonally dominant), so positive semidefinite, and equal to w_i where
/// no weight is negative (they sum to 1).
struct VertexWeights {
    std::array<double, 8> force{};     ///< trilinear, hex8 corner order
    std::array<double, 8> stiffness{}; ///< |w_i| sum_j |w_j|
};
/// The weights of a point at `local` (its element's cell coordinates, [0, 1]^3 inside).
[[nodiscard]] VertexWeights vertex_weights(const Eigen::Vector3d& local);

/// The contact's forces gathered on the nodes of `surface`'s model: each point's force shared by
/// the corners of its element with the trilinear weights, the penalty stiffness lumped by the
/// stiffness weights above. After a cut has rebuilt the model, this carries a contact over to the
/// new nodes; points whose surface vertex the cut replaced are dropped (the next frame finds the
/// new ones).
[[nodiscard]] std::vector<fem::NodeContact> node_contacts(const ModelSurface& surface, const SurfaceContact& contact);

/// Fills `out` with the surface points within `box` (world mm) of the surface deformed by
/// `node_positions` (m), each with its area and outward normal: the snapshot the haptic thread
/// touches. At most out.capacity() points (out.truncated says when more were there). With
/// `node_stiffness` (per node, N/mm per cm^2 of contact), each point's contact stiffness is its
/// value interpolated where the point is embedded; without, the snapshot leaves it to the tool.
void sample_surface(const ModelSurface& surface, const std::vector<Eigen::Vector3d>& node_positions, const Eigen::AlignedBox3d& box,
                    contact::SurfacePoints& out, const std::vector<double>* node_stiffness = nullptr);

/// Adds `b`'s node contacts to `a` (several tools on one object).
void merge_node_contacts(std::vector<fem::NodeContact>& a, const std::vector<fem::NodeContact>& b);

} // namespace vox::cut
