// "levels": "auto" with a budget: judged on whole frames while the tools work (a burr drilling a
// block), each level on its own copy of the grid; the preconditioner each level was fastest
// with is reported; a budget no level meets takes the coarsest and says so.

#include "grid/label_grid.hpp"
#include "io/scene.hpp"
#include "io/scene_object.hpp"
#include "sim/dbg_simulation.hpp"
#include "sim/level_choice.hpp"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

namespace vox::sim {
namespace {

/// A 20 mm block of 1 mm voxels held at its base; a burr drills into the top from frame 5 on.
io::Scene drilled_block(double budget_ms)
{
    const nlohmann::json doc = {
        {"object", {{"phantom", {{"shape", "block"}}}, {"levels", "auto"}, {"step_budget_ms", budget_ms}}},
        {"materials", {{"default", {{"youngs_modulus_pa", 1e7}, {"poisson_ratio", 0.3}, {"density_kg_m3", 1900}}}}},
        {"solver", {{"type", "dbg"}, {"dt_s", 0.01}}},
        {"constraints", {{{"type", "fixed"}, {"box_mm", {{-1, -1, -1}, {20, 20, 0}}}}}},
        {"tools", {{{"name", "burr"}, {"shape", "sphere"}, {"radius_mm", 3.0}, {"action", "drill"}, {"burr_speed_rpm", 60000}}}},
        {"script",
         {{{"t_s", 0.0}, {"tool", "burr"}, {"position_mm", {9.5, 9.5, 30}}},
          {{"t_s", 0.1}, {"tool", "burr"}, {"position_mm", {9.5, 9.5, 21.5}}},
          {{"t_s", 0.5}, {"tool", "burr"}, {"position_mm", {9.5, 9.5, 18}}}}},
    };
    return io::parse_scene(doc, ::testing::TempDir(), "auto_drill.json");
}

TEST(LevelChoice, JudgesWholeFramesWhileTheToolsWorkOnCopiesOfTheGrid)
{
    const double budget_ms = 5.0;
    const io::Scene scene = drilled_block(budget_ms);
    auto labels = std::make_shared<const grid::LabelGrid>(io::load_scene_object(scene));
    const grid::BranchedGrid grid = build_scene_grid(scene, *labels, 6);
    const std::size_t voxels = grid.voxels().alive_count();
    const LevelChoice c = choose_level(scene, grid, labels);
    EXPECT_EQ(grid.voxels().alive_count(), voxels) << "the trials drilled the run's own grid";
    ASSERT_FALSE(c.trials.empty());
    EXPECT_NE(c.reason.find("tools at work"), std::string::npos) << c.reason;
    // Levels are tried from the coarsest down: the chosen one fits, and so does every coarser one;
    // the search ends at the finest tried or at the first that does not fit.
    const LevelTrial& last = c.trials.back();
    EXPECT_EQ(c.level, last.frame_ms <= budget_ms ? last.level : c.trials[c.trials.size() - 2].level);
    for (const LevelTrial& t : c.trials) {
        if (t.level >= c.level) EXPECT_LE(t.frame_ms, budget_ms);
        EXPECT_GE(t.frame_ms, t.step_ms) << "a whole frame holds its step";
        EXPECT_NE(t.preconditioner, io::PreconditionerChoice::automatic) << "the fastest one is named";
    }
    for (const LevelTrial& t : c.trials)
        if (t.level == c.level) EXPECT_EQ(c.preconditioner, t.preconditioner);
}

TEST(LevelChoice, ABudgetNoLevelMeetsTakesTheCoarsestAndSaysSo)
{
    const io::Scene scene = drilled_block(1e-3);
    auto labels = std::make_shared<const grid::LabelGrid>(io::load_scene_object(scene));
    const grid::BranchedGrid grid = build_scene_grid(scene, *labels, 6);
    const LevelChoice c = choose_level(scene, grid, labels);
    ASSERT_EQ(c.trials.size(), 1u);
    EXPECT_EQ(c.level, c.trials.front().level);
    EXPECT_NE(c.reason.find("no level"), std::string::npos) << c.reason;
}

} // namespace
} // namespace vox::sim
