#pragma once
// Another model stepping the nodes an ImplicitSolver holds (shape matching: shape/shape_matching.hpp).
// The solver keeps everything the rest of the product sets on the nodes (what is held or asleep,
// gravity, point loads, tool and pair contacts, water) and hands its step to the integrator, so
// the branched grid's cuts, state transfer, contact and sleep serve it unchanged.

#include "fem/implicit_solver.hpp"

namespace vox::fem {

class NodeIntegrator {
public:
    virtual ~NodeIntegrator() = default;
    /// One frame: moves solver.positions() and solver.velocities() by the solver's dt and loads
    /// (positions only, every frame to equilibrium, in the quasi-static mode).
    virtual StepStats step(ImplicitSolver& solver) = 0;
    /// A line for the log: what steps the nodes.
    [[nodiscard]] virtual std::string description() const = 0;
};

} // namespace vox::fem
