#pragma once
// "levels": "auto": the run picks the coarsening level itself and says why.
//  - step_budget_ms: a budget for the whole frame (tools, cuts and the step). The finest level
//    whose frames fit it, judged on the frames the scene will have: from the first frame in which
//    a tool touches the object (found by running the script at the coarsest level), with their
//    contact and cuts; frames at rest when no tool ever touches it. Each level is timed on its own
//    copy of the grid (the 90th percentile of 20 frames after 2 of warm-up), with each
//    preconditioner when the scene says "auto" (the fastest is kept, and the run uses it). Levels
//    are tried from the coarsest down and the search stops at the first that does not fit.
//  - max_error: the coarsest level whose quasi-static deformation under the scene's loads differs
//    from the next finer level's by at most max_error (RMS of the surface displacement difference
//    over the finer level's RMS displacement).

#include "grid/branched_grid.hpp"
#include "grid/label_grid.hpp"
#include "io/scene.hpp"

#include <memory>
#include <string>
#include <vector>

namespace vox::sim {

struct LevelTrial {
    int level = 0;
    std::size_t dofs = 0;
    double step_ms = 0.0;  ///< budget: median measured solver step
    double error = -1.0;   ///< max_error: difference from the next finer level (-1: not measured)
    double frame_ms = 0.0; ///< budget: whole frame, 90th percentile of the judged frames
    io::PreconditionerChoice preconditioner = io::PreconditionerChoice::automatic; ///< budget: the fastest
    std::string linear_solver; ///< budget: what it resolved to ("CG, warped Cholesky preconditioner", ...)
};

struct LevelChoice {
    int level = 3;
    /// budget: the preconditioner the chosen level was fastest with (the run uses it).
    io::PreconditionerChoice preconditioner = io::PreconditionerChoice::automatic;
    std::string reason;
    std::vector<LevelTrial> trials;
    std::vector<int> unusable; ///< levels the scene cannot be simulated at (a wet region holding no element's centre there)
};

/// `grid` must hold levels up to 6 (or its object's coarsest). Throws the scene's InputError when
/// max_error is asked of an object nothing holds (its equilibrium is undefined).
/// `labels` are the grid's (trials build methods on copies of the grid).
[[nodiscard]] LevelChoice choose_level(const io::Scene& scene, const grid::BranchedGrid& grid,
                                       std::shared_ptr<const grid::LabelGrid> labels);

} // namespace vox::sim
