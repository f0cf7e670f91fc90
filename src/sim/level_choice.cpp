#include "sim/level_choice.hpp"

#include "sim/dbg_simulation.hpp"
#include "core/error.hpp"
#include "core/log.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <memory>

namespace vox::sim {
namespace {

/// Levels worth trying: 1 .. max, plus 0 for objects small enough to simulate voxel by voxel.
int finest_level(const grid::BranchedGrid& grid) { return grid.voxels().alive_count() <= 200000 ? 0 : 1; }

std::string format_ms(double ms)
{
    char text[32];
    std::snprintf(text, sizeof text, "%.2f ms", ms);
    return text;
}

std::string percent(double fraction)
{
    char text[32];
    std::snprintf(text, sizeof text, "%.2f %%", 100.0 * fraction);
    return text;
}

LevelChoice by_budget(const io::Scene& scene, const grid::BranchedGrid& grid, double budget_ms)
{
    // A budget is for interactive stepping: time dynamic steps even for a static scene (a
    // converged static frame costs next to nothing and would make every level "fit").
    io::Scene dynamic = scene;
    dynamic.solver.mode = io::SolverMode::dynamic;
    LevelChoice out;
    const int finest = finest_level(grid);
    double previous_ms = 0.0;
    std::size_t previous_elements = 0;
    for (int level = grid.max_level(); level >= finest; --level) {
        // Skip levels predicted (from the element count) to take over 20 budgets: measuring them
        // would take long and they could not be chosen.
        const std::size_t elements = level == 0 ? grid.voxels().alive_count() : grid.level(level).elements.size();
        if (previous_elements && previous_ms * static_cast<double>(elements) / static_cast<double>(previous_elements) > 20 * budget_ms)
            break;
        // A scene whose boxes catch nothing at a coarse level can still run at a finer one.
        std::unique_ptr<DbgSimulation> sim;
        try {
            sim = std::make_unique<DbgSimulation>(dynamic, grid, level);
        } catch (const InputError& e) {
            log::info("levels auto: level {} skipped: {}", level, e.what());
            continue;
        }
        sim->step(); // warm-up: first factorisations, caches
        std::vector<double> ms;
        for (int k = 0; k < 3; ++k) ms.push_back(sim->step().step_ms);
        std::sort(ms.begin(), ms.end());
        out.trials.push_back({level, sim->solver().dof_count(), ms[1], -1.0});
        log::info("levels auto: level {} steps in {:.2f} ms ({} DOFs)", level, ms[1], sim->solver().dof_count());
        if (ms[1] > budget_ms) break;
        previous_ms = ms[1];
        previous_elements = elements;
    }
    if (out.trials.empty()) throw scene.error("object.levels", "no level can simulate this scene (see the messages above)");
    const auto fits = std::find_if(out.trials.rbegin(), out.trials.rend(), [&](const LevelTrial& t) { return t.step_ms <= budget_ms; });
    if (fits == out.trials.rend()) {
        out.level = out.trials.front().level;
        out.reason = "no level steps within " + format_ms(budget_ms) + "; the coarsest, level " + std::to_string(out.level) +
                     ", takes " + format_ms(out.trials.front().step_ms);
    } else {
        out.level = fits->level;
        out.reason = "level " + std::to_string(out.level) + " is the finest whose step (" + format_ms(fits->step_ms) +
                     ") fits the budget of " + format_ms(budget_ms);
        if (fits != out.trials.rbegin())
            out.reason += "; level " + std::to_string(out.trials.back().level) + " takes " + format_ms(out.trials.back().step_ms);
    }
    return out;
}

/// Quasi-static surface displacements at one level, m, per surface vertex slot.
std::vector<Eigen::Vector3d> static_displacements(const io::Scene& scene, const grid::BranchedGrid& grid, int level, std::size_t& dofs)
{
    io::Scene s = scene;
    s.solver.mode = io::SolverMode::static_equilibrium;
    s.solver.cg_max_iterations = std::max(s.solver.cg_max_iterations, 5000);
    DbgSimulation sim(s, grid, level);
    sim.step();
    dofs = sim.solver().dof_count();
    return sim.surface().displacements(sim.solver().positions());
}

LevelChoice by_error(const io::Scene& scene, const grid::BranchedGrid& grid, double max_error)
{
    if (scene.constraints.empty())
        throw scene.error("object.max_error", "comparing levels needs the object held (constraints): "
                                              "a free object has no equilibrium to compare");
    LevelChoice out;
    const int finest = finest_level(grid);
    // Start at the coarsest level the scene's boxes can use.
    std::size_t dofs = 0;
    int start = grid.max_level();
    std::vector<Eigen::Vector3d> coarse;
    for (; start > finest; --start) {
        try {
            coarse = static_displacements(scene, grid, start, dofs);
            break;
        } catch (const InputError& e) {
            log::info("levels auto: level {} skipped: {}", start, e.what());
        }
    }
    for (int level = start; level > finest; --level) {
        std::size_t finer_dofs = 0;
        const std::vector<Eigen::Vector3d> finer = static_displacements(scene, grid, level - 1, finer_dofs);
        double diff = 0.0, norm = 0.0;
        for (std::size_t i = 0; i < finer.size(); ++i) {
            diff += (coarse[i] - finer[i]).squaredNorm();
            norm += finer[i].squaredNorm();
        }
        const double error = norm > 0.0 ? std::sqrt(diff / norm) : 0.0;
        out.trials.push_back({level, dofs, 0.0, error});
        log::info("levels auto: level {} differs from level {} by {:.2f} %", level, level - 1, 100 * error);
        if (error <= max_error) {
            out.level = level;
            out.reason = "level " + std::to_string(level) + " is the coarsest whose deformation differs from level " +
                         std::to_string(level - 1) + "'s by at most " + percent(max_error) + " (" + percent(error) + ")";
            return out;
        }
        coarse = finer;
        dofs = finer_dofs;
    }
    out.level = finest;
    out.reason = "no coarser level stays within " + percent(max_error) + " of the next finer one; using level " +
                 std::to_string(finest);
    return out;
}

} // namespace

LevelChoice choose_level(const io::Scene& scene, const grid::BranchedGrid& grid)
{
    if (scene.object.step_budget_ms) return by_budget(scene, grid, *scene.object.step_budget_ms);
    return by_error(scene, grid, scene.object.max_error.value_or(0.05));
}

} // namespace vox::sim
