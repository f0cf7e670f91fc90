// voxsculpt bench drilling: the whole frame (tools, the drill's removal, the model's update and
// the step: the frame loop's own frame_ms) while a burr drills through the bundled CT-like
// skull, with the bone elastic (E 15 GPa) and rigid. Each run opens the scene afresh with
// "levels": "auto" and a 16 ms budget, so the level and preconditioner are chosen as a user's
// run would choose them, then replays the whole script with the level governor a device run has
// (it moves coarser while frames miss the budget, where the scene can be simulated coarser). Reported over the frames that removed
// bone, and over all frames: median, 95th percentile and largest.

#include "bench/harness/drilling.hpp"

#include "core/atomic_file.hpp"
#include "core/sample_stats.hpp"
#include "core/stopwatch.hpp"
#include "io/scene_object.hpp"
#include "sim/frame_loop.hpp"
#include "sim/level_choice.hpp"
#include "sim/level_governor.hpp"
#include "sim/method_factory.hpp"

#include <nlohmann/json.hpp>

#include <cmath>
#include <cstdio>
#include <fstream>
#include <sstream>

namespace vox::bench {
namespace {

constexpr double k_budget_ms = 16.0;

struct DrillingRun {
    std::string bone;
    int level = 0;
    std::string linear_solver;
    std::size_t drilling_frames = 0, removed_voxels = 0;
    double drilling_p50 = 0, drilling_p95 = 0, drilling_max = 0;
    double all_p50 = 0, all_p95 = 0;
    double choice_s = 0; ///< the level choice's own trials
    int level_changes = 0;
    int final_level = 0;
};

DrillingRun drill_once(const char* file, const char* bone)
{
    io::Scene scene = io::load_scene(VOX_DATA_DIR "/scenes/" + std::string(file));
    scene.object.auto_levels = true;
    scene.object.step_budget_ms = k_budget_ms;
    const auto labels = std::make_shared<const grid::LabelGrid>(io::load_scene_object(scene));
    DrillingRun r;
    r.bone = bone;
    Stopwatch clock;
    sim::OpenedMethod opened = sim::open_method(scene, labels);
    r.choice_s = clock.lap() / 1e3;
    r.level = opened.method->level();
    r.linear_solver = opened.method->linear_solver();
    sim::ToolPolicy tools(scene);
    sim::FrameLoop loop(scene, *opened.method, tools);
    if (auto governor = sim::level_governor(scene, *opened.choice, opened.method->coarsest_level())) loop.govern_levels(std::move(*governor));
    const int frames = static_cast<int>(std::ceil(scene.script.back().t_s / scene.solver.dt_s - 1e-9));
    std::vector<double> all, drilling;
    for (int f = 1; f <= frames; ++f) {
        const sim::FrameStats s = loop.next();
        const double ms = s.frame_ms;
        all.push_back(ms);
        r.level_changes += s.level_change.has_value();
        if (s.tools.cut.removed_voxels == 0) continue;
        drilling.push_back(ms);
        r.removed_voxels += s.tools.cut.removed_voxels;
    }
    r.drilling_frames = drilling.size();
    r.final_level = opened.method->level();
    r.drilling_p50 = quantile(drilling, 0.5);
    r.drilling_p95 = quantile(drilling, 0.95);
    r.drilling_max = quantile(drilling, 1.0);
    r.all_p50 = quantile(all, 0.5);
    r.all_p95 = quantile(all, 0.95);
    return r;
}

} // namespace

void run_drilling_bench(int runs, const std::filesystem::path& dir)
{
    std::vector<DrillingRun> results;
    for (int run = 1; run <= runs; ++run)
        for (const auto& [file, bone] : {std::pair{"skull_burr_hole.json", "elastic, E 15 GPa"}, std::pair{"skull_burr_hole_rigid.json", "rigid"}}) {
            results.push_back(drill_once(file, bone));
            const DrillingRun& r = results.back();
            std::printf("run %d, %s: level %d, drilling frames %.2f / %.2f / %.2f ms\n", run, bone, r.level, r.drilling_p50, r.drilling_p95,
                        r.drilling_max);
            std::fflush(stdout);
        }
    std::ostringstream md;
    md << "# Drilling a burr hole (`voxsculpt bench drilling`)\n\n"
          "The burr of `data/scenes/skull_burr_hole.json` (a 5 mm sphere at 60,000 rpm pressed 16 mm down "
          "through the vertex of the bundled CT-like skull in 3 s, 350 frames of 10 ms) with the bone "
          "elastic (E 15 GPa) and rigid (`skull_burr_hole_rigid.json`). Every run opens the scene with "
          "`\"levels\": \"auto\"` and `\"step_budget_ms\": 16` (the level and preconditioner chosen as a "
          "user's run chooses them, on frames with the burr at work) and replays the script with the level "
          "governor of a device run (one level coarser while the frames of a second miss the budget, where the "
          "skull can still be held at its base). A frame is "
          "timed whole around the frame loop: the burr's contact, the bone it removes, the grid, surface "
          "and model updates, and the step. Machine: "
       << machine_description() << ".\n\n";
    md << "| run | bone | level, solver | frames removing bone | voxels removed | those frames: median / p95 / max (ms) | "
          "all frames: median / p95 (ms) | level choice (s) | level moves (final level) |\n|---|---|---|---|---|---|---|---|---|\n";
    nlohmann::json j = nlohmann::json::array();
    for (std::size_t k = 0; k < results.size(); ++k) {
        const DrillingRun& r = results[k];
        char line[512];
        std::snprintf(line, sizeof line, "| %zu | %s | %d, %s | %zu | %zu | %.2f / %.2f / %.2f | %.2f / %.2f | %.1f | %d (%d) |\n", k / 2 + 1,
                      r.bone.c_str(), r.level, r.linear_solver.c_str(), r.drilling_frames, r.removed_voxels, r.drilling_p50, r.drilling_p95,
                      r.drilling_max, r.all_p50, r.all_p95, r.choice_s, r.level_changes, r.final_level);
        md << line;
        j.push_back({{"run", k / 2 + 1}, {"bone", r.bone}, {"level", r.level}, {"linear_solver", r.linear_solver},
                     {"drilling_frames", r.drilling_frames}, {"removed_voxels", r.removed_voxels},
                     {"drilling_frame_ms", {{"median", r.drilling_p50}, {"p95", r.drilling_p95}, {"max", r.drilling_max}}},
                     {"frame_ms", {{"median", r.all_p50}, {"p95", r.all_p95}}}, {"level_choice_s", r.choice_s},
                     {"level_changes", r.level_changes}, {"final_level", r.final_level},
                     {"budget_ms", k_budget_ms}, {"machine", machine_description()}});
    }
    md << "\nMedian over the runs of each row's p95 while drilling:";
    for (const char* bone : {"elastic, E 15 GPa", "rigid"}) {
        std::vector<double> p95;
        for (const DrillingRun& r : results)
            if (r.bone == bone) p95.push_back(r.drilling_p95);
        char text[128];
        std::snprintf(text, sizeof text, " %s %.2f ms (%.2f - %.2f);", bone, quantile(p95, 0.5), quantile(p95, 0.0), quantile(p95, 1.0));
        md << text;
    }
    md << " budget " << k_budget_ms << " ms.\n";
    std::filesystem::create_directories(dir);
    write_atomically(dir / "drilling.md", [&](const std::filesystem::path& tmp) { std::ofstream(tmp) << md.str(); });
    write_atomically(dir / "drilling.json", [&](const std::filesystem::path& tmp) { std::ofstream(tmp) << j.dump(1) << '\n'; });
    std::printf("%s\nwrote %s and %s\n", md.str().c_str(), (dir / "drilling.md").c_str(), (dir / "drilling.json").c_str());
}

} // namespace vox::bench
