#pragma once
// Carrying the simulation over a cut without a restart: after BranchedGrid::update the model of
// the simulated level is rebuilt, and every new node takes the position and velocity of the old
// node at the same corner of the element it came from (a node split by the cut hands its state to
// both halves), every new element the water content and plastic strain of its source.

#include "fem/implicit_solver.hpp"
#include "grid/branched_grid.hpp"

namespace vox::cut {

/// `report` is what grid.update returned; the old model and solver are from before it, the new
/// ones are built on the updated grid at the same level.
void transfer_state(const grid::UpdateReport& report, const fem::HexModel& old_model, const fem::ImplicitSolver& old_solver,
                    const fem::HexModel& new_model, fem::ImplicitSolver& new_solver);

} // namespace vox::cut
