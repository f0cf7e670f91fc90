#pragma once
// Carrying the simulation on without a restart:
//  - over a cut: after BranchedGrid::update the model of the simulated level is rebuilt, and every
//    new node takes the position and velocity of the old node at the same corner of the element it
//    came from (a node split by the cut hands its state to both halves), every new element the
//    water content and plastic strain of its source;
//  - to another level of the same grid (a run that moves to a coarser level when its frames miss
//    their budget, and back): every new node takes the displacement and velocity the old level's
//    field has at its rest position, every new element the mean water and plastic strain of the
//    old elements holding its voxels.

#include "fem/implicit_solver.hpp"
#include "grid/branched_grid.hpp"

namespace vox::cut {

/// `report` is what grid.update returned; the old model and solver are from before it, the new
/// ones are built on the updated grid at the same level.
void transfer_state(const grid::UpdateReport& report, const fem::HexModel& old_model, const fem::ImplicitSolver& old_solver,
                    const fem::HexModel& new_model, fem::ImplicitSolver& new_solver);

/// `old_model` and `new_model` are two levels (>= 1) of `grid`. A new node's displacement and
/// velocity are the old field's, trilinear in the old element that holds the voxel of the new
/// element nearest that corner (extrapolated when the corner lies outside it): exact for any
/// affine field, so a rigid motion or a uniform stretch carries over unchanged, and the same for
/// every superimposed element, since each follows the material it holds. Water content and
/// plastic strain are averaged over the new element's voxels.
void transfer_between_levels(const grid::BranchedGrid& grid, const fem::HexModel& old_model, const fem::ImplicitSolver& old_solver,
                             const fem::HexModel& new_model, fem::ImplicitSolver& new_solver);

} // namespace vox::cut
