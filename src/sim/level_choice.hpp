#pragma once
// "levels": "auto": the run picks the coarsening level itself and says why.
//  - step_budget_ms: the finest level whose measured dynamic step (median of three after a
//    warm-up) fits the budget; levels are tried from the coarsest down and the search stops at
//    the first that does not fit (finer levels only cost more).
//  - max_error: the coarsest level whose quasi-static deformation under the scene's loads differs
//    from the next finer level's by at most max_error (RMS of the surface displacement difference
//    over the finer level's RMS displacement).

#include "grid/branched_grid.hpp"
#include "io/scene.hpp"

#include <string>
#include <vector>

namespace vox::sim {

struct LevelTrial {
    int level = 0;
    std::size_t dofs = 0;
    double step_ms = 0.0;  ///< budget: median measured step
    double error = -1.0;   ///< max_error: difference from the next finer level (-1: not measured)
};

struct LevelChoice {
    int level = 3;
    std::string reason;
    std::vector<LevelTrial> trials;
};

/// `grid` must hold levels up to 6 (or its object's coarsest). Throws the scene's InputError when
/// max_error is asked of an object nothing holds (its equilibrium is undefined).
[[nodiscard]] LevelChoice choose_level(const io::Scene& scene, const grid::BranchedGrid& grid);

} // namespace vox::sim
