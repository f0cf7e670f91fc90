#include "sim/level_choice.hpp"

#include "sim/dbg_method.hpp"
#include "sim/dbg_simulation.hpp"
#include "sim/frame_loop.hpp"
#include "core/error.hpp"
#include "core/log.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <memory>
#include <optional>

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

/// Frames timed per trial, after the warm-up ones (see time_frames).
constexpr int k_warm_up_frames = 2;
constexpr int k_timed_frames = 20;

/// The first frame (from 1) in which a tool of the scene cuts (or drills) the object, found by
/// moving the tools along the script over `method` held at rest (so that a coarse level's own
/// motion cannot carry the object away from them); without cuts, the first in which a tool
/// touches it; 0 when no tool touches it within the script.
int first_working_frame(const io::Scene& scene, Method& method)
{
    if (scene.script.empty()) return 0;
    const int frames = static_cast<int>(std::ceil(scene.script.back().t_s / scene.solver.dt_s - 1e-9));
    ToolPolicy tools(scene);
    int touched = 0;
    for (int f = 1; f <= frames; ++f) {
        const ToolsFrame s = tools.frame(method, f * scene.solver.dt_s, scene.solver.dt_s);
        if (s.cut.changed()) return f;
        for (const ToolFrame& t : s.tools)
            if (!touched && t.force_n.squaredNorm() > 0.0) touched = f;
    }
    return touched;
}

struct FrameTimes {
    double frame_ms = 0.0; ///< the 90th percentile (the 18th of 20, sorted)
    double step_ms = 0.0;  ///< median solver step
};

/// Whole-frame times (tools, cuts, step) on `method` from frame `from` on (0: from the start).
/// A frame over `give_up_ms` ends the trial: that level and preconditioner cannot be chosen.
FrameTimes time_frames(const io::Scene& scene, Method& method, int from, double give_up_ms)
{
    ToolPolicy tools(scene);
    FrameLoop loop(scene, method, tools);
    loop.go_on_from(std::max(0, from - 1 - k_warm_up_frames));
    // Warm-up: first factorisations and caches, and the first cut, whose allocations fault in
    // memory the later ones reuse (it took 40 ms on the skull where the next took 4).
    bool cut = from == 0;
    for (int k = 0; k < k_warm_up_frames || (!cut && k < k_warm_up_frames + 8); ++k) cut = loop.next().tools.cut.changed() || cut;
    std::vector<double> frame, step;
    for (int k = 0; k < k_timed_frames; ++k) {
        const FrameStats s = loop.next();
        frame.push_back(s.frame_ms);
        step.push_back(s.step.step_ms);
        if (frame.back() > give_up_ms) return {frame.back(), step.back()};
    }
    std::sort(frame.begin(), frame.end());
    std::sort(step.begin(), step.end());
    return {frame[frame.size() * 9 / 10 - 1], step[step.size() / 2]};
}

LevelChoice by_budget(const io::Scene& scene, const grid::BranchedGrid& grid, std::shared_ptr<const grid::LabelGrid> labels,
                      double budget_ms)
{
    // A budget is for interactive stepping: time dynamic steps even for a static scene (a
    // converged static frame costs next to nothing and would make every level "fit").
    io::Scene dynamic = scene;
    dynamic.solver.mode = io::SolverMode::dynamic;
    dynamic.object.auto_levels = false;
    LevelChoice out;
    const int finest = finest_level(grid);
    // The frames judged are those the scene will have: from the first in which a tool touches the
    // object (found at the coarsest level that can simulate it), with their contact and cuts.
    int working = -1;
    double previous_ms = 0.0;
    std::size_t previous_elements = 0;
    for (int level = grid.max_level(); level >= finest; --level) {
        // Skip levels predicted (from the element count) to take over 20 budgets: measuring them
        // would take long and they could not be chosen.
        const std::size_t elements = level == 0 ? grid.voxels().alive_count() : grid.level(level).elements.size();
        if (previous_elements && previous_ms * static_cast<double>(elements) / static_cast<double>(previous_elements) > 20 * budget_ms)
            break;
        std::vector<io::PreconditionerChoice> candidates{scene.solver.preconditioner};
        if (scene.solver.preconditioner == io::PreconditionerChoice::automatic) {
            candidates = {io::PreconditionerChoice::cholesky, io::PreconditionerChoice::jacobi};
            if (level < grid.max_level()) candidates.push_back(io::PreconditionerChoice::multigrid);
        }
        std::optional<LevelTrial> best;
        std::vector<std::string> tried; // a rigid object leaves nothing to solve: one trial does
        for (io::PreconditionerChoice p : candidates) {
            dynamic.solver.preconditioner = p;
            dynamic.object.levels = level;
            // Each trial on its own copy of the grid: its cuts must not reach the run's.
            std::unique_ptr<DbgMethod> method;
            try {
                method = std::make_unique<DbgMethod>(dynamic, labels, std::make_unique<grid::BranchedGrid>(grid.copy()), level);
                if (working < 0) {
                    working = first_working_frame(dynamic, *method);
                    log::info("levels auto: judged on {}", working > 0 ? "the frames from " + std::to_string(working) +
                                                                             ", where the tools first work on the object"
                                                                       : std::string("frames at rest (no tool touches the object)"));
                    method = std::make_unique<DbgMethod>(dynamic, labels, std::make_unique<grid::BranchedGrid>(grid.copy()), level);
                }
            } catch (const InputError& e) { // a scene a coarse level cannot run (a wet region holding no element's centre there) may run at a finer one
                log::info("levels auto: level {} skipped: {}", level, e.what());
                out.unusable.push_back(level);
                break;
            }
            if (std::find(tried.begin(), tried.end(), method->linear_solver()) != tried.end()) continue;
            tried.push_back(method->linear_solver());
            const FrameTimes t = time_frames(dynamic, *method, working, 10.0 * budget_ms);
            log::info("levels auto: level {} with {}: frames take {:.2f} ms (90th percentile; solver step {:.2f} ms, {} DOFs)", level,
                      method->linear_solver(), t.frame_ms, t.step_ms, method->dof_count());
            if (!best || t.frame_ms < best->frame_ms)
                best = LevelTrial{level, method->dof_count(), t.step_ms, -1.0, t.frame_ms, p, method->linear_solver()};
        }
        if (!best) continue;
        out.trials.push_back(*best);
        if (best->frame_ms > budget_ms) break;
        previous_ms = best->frame_ms;
        previous_elements = elements;
    }
    if (out.trials.empty()) throw scene.error("object.levels", "no level can simulate this scene (see the messages above)");
    const auto fits = std::find_if(out.trials.rbegin(), out.trials.rend(), [&](const LevelTrial& t) { return t.frame_ms <= budget_ms; });
    const std::string judged = working > 0 ? "frames with the tools at work" : "frames at rest";
    const auto with = [&](const LevelTrial& t) {
        return format_ms(t.frame_ms) + " (" + t.linear_solver + ")";
    };
    const LevelTrial& chosen = fits == out.trials.rend() ? out.trials.front() : *fits;
    out.level = chosen.level;
    out.preconditioner = chosen.preconditioner;
    if (fits == out.trials.rend()) {
        out.reason = "no level's " + judged + " fit " + format_ms(budget_ms) + "; the coarsest, level " + std::to_string(out.level) +
                     ", takes " + with(chosen);
    } else {
        out.reason = "level " + std::to_string(out.level) + " is the finest whose " + judged + " (90th percentile: " + with(chosen) +
                     ") fit the budget of " + format_ms(budget_ms);
        if (fits != out.trials.rbegin())
            out.reason += "; level " + std::to_string(out.trials.back().level) + " takes " + format_ms(out.trials.back().frame_ms);
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
        out.trials.push_back({level, dofs, 0.0, error, 0.0, io::PreconditionerChoice::automatic, {}});
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

LevelChoice choose_level(const io::Scene& scene, const grid::BranchedGrid& grid, std::shared_ptr<const grid::LabelGrid> labels)
{
    if (scene.object.step_budget_ms) return by_budget(scene, grid, std::move(labels), *scene.object.step_budget_ms);
    return by_error(scene, grid, scene.object.max_error.value_or(0.05));
}

} // namespace vox::sim
