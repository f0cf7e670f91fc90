// voxsculpt bench cutting: how long a cutting frame takes on the liver at level 4 during the 5 cm
// incision of data/scenes/liver_incision.json, each frame in which the scalpel cut. Two figures:
// the cut's own phases (collision of the tool with the surface + propagation, the faces its
// section crossed + grid update + local remesh: the branched-grid paper's phases, target 5 ms),
// and the whole frame a user feels (the frame loop's frame_ms: those phases, the model's update
// after the cut and the solver's step; target 16.7 ms, 60 Hz). Each run replays the whole scene
// from scratch in three configurations in turn: as bundled (Jacobi, matrix-free, nothing to keep
// across a cut; pieces not touching), with piece contact on (the incision's walls pressing on
// each other, as a user who turns it on feels the frame), and with it on and the warped Cholesky
// factor, which a cut patches instead of taking anew. Run it pinned to one core
// (`taskset -c 0`) for the one-core figure.

#include "bench/harness/cutting.hpp"

#include "core/atomic_file.hpp"
#include "core/sample_stats.hpp"
#include "io/scene_object.hpp"
#include "sim/frame_loop.hpp"
#include "sim/method_factory.hpp"

#include <nlohmann/json.hpp>

#include <cmath>
#include <cstdio>
#include <fstream>
#include <sstream>

namespace vox::bench {
namespace {

struct CuttingRun {
    std::string preconditioner, linear_solver;
    std::size_t cutting_frames = 0, faces = 0;
    double phases_p50 = 0, phases_p95 = 0;          ///< collision + propagation + grid update + remesh
    double whole_p50 = 0, whole_p95 = 0, whole_max = 0;
    double model_update_p50 = 0, step_p50 = 0, cg_p50 = 0; ///< on cutting frames
};

CuttingRun cut_once(const io::Scene& scene, const std::shared_ptr<const grid::LabelGrid>& labels, const char* preconditioner)
{
    const int frames = static_cast<int>(std::ceil(scene.script.back().t_s / scene.solver.dt_s - 1e-9));
    const std::unique_ptr<sim::Method> method = sim::open_method(scene, labels).method;
    sim::ToolPolicy tools(scene);
    sim::FrameLoop loop(scene, *method, tools);
    std::vector<double> phases, whole, update, step, cg;
    CuttingRun r;
    r.preconditioner = preconditioner;
    r.linear_solver = method->linear_solver();
    for (int f = 1; f <= frames; ++f) {
        const sim::FrameStats s = loop.next();
        const sim::CutFigures& c = s.tools.cut;
        if (!c.changed()) continue;
        phases.push_back(s.tools.cutting_ms());
        whole.push_back(s.frame_ms);
        update.push_back(c.fem_update_ms);
        step.push_back(s.step.step_ms);
        cg.push_back(s.step.cg_iterations);
        r.faces += c.separated_faces;
    }
    r.cutting_frames = whole.size();
    r.phases_p50 = quantile(phases, 0.5);
    r.phases_p95 = quantile(phases, 0.95);
    r.whole_p50 = quantile(whole, 0.5);
    r.whole_p95 = quantile(whole, 0.95);
    r.whole_max = quantile(whole, 1.0);
    r.model_update_p50 = quantile(update, 0.5);
    r.step_p50 = quantile(step, 0.5);
    r.cg_p50 = quantile(cg, 0.5);
    return r;
}

} // namespace

void run_cutting_bench(int runs, const std::filesystem::path& dir)
{
    const io::Scene scene = io::load_scene(VOX_DATA_DIR "/scenes/liver_incision.json");
    const auto labels = std::make_shared<const grid::LabelGrid>(io::load_scene_object(scene));
    // The scene as bundled, then with pieces touching (the walls of the incision press on each
    // other), with its Jacobi preconditioner and with the warped Cholesky factor.
    io::Scene touching = scene;
    touching.piece_contact.enabled = true;
    io::Scene cholesky = touching;
    cholesky.solver.preconditioner = io::PreconditionerChoice::cholesky;
    const std::vector<std::pair<const char*, const io::Scene*>> configurations = {
        {"jacobi (the scene's)", &scene}, {"jacobi, piece contact", &touching}, {"cholesky, piece contact", &cholesky}};
    std::vector<CuttingRun> results;
    for (int run = 1; run <= runs; ++run)
        for (const auto& [name, s] : configurations) {
            results.push_back(cut_once(*s, labels, name));
            const CuttingRun& r = results.back();
            std::printf("run %d, %s: %zu cutting frames, whole frame %.1f / %.1f / %.1f ms, cut phases p95 %.2f ms\n", run, name, r.cutting_frames,
                        r.whole_p50, r.whole_p95, r.whole_max, r.phases_p95);
            std::fflush(stdout);
        }
    std::ostringstream md;
    md << "# Cutting (`voxsculpt bench cutting`)\n\n"
          "The 5 cm scalpel incision of `data/scenes/liver_incision.json` (the liver, label 255, at level "
       << scene.object.levels
       << ", separate mode), replayed from scratch in each configuration in turn, alternating: the scene as bundled (Jacobi, "
          "pieces not touching), with `piece_contact` on, and with it on and the warped Cholesky factor. A cutting frame is a frame "
          "in which the scalpel cut. *Cut phases*: collision + propagation + grid update + local remesh (the "
          "branched-grid paper's phases; target p95 under 5 ms). *Whole frame*: the frame loop's wall clock, those phases, "
          "the model's update after the cut and the solver's step (target p95 under 16.7 ms, 60 Hz). Machine: "
       << machine_description() << ".\n\n";
    md << "| run | configuration | cutting frames | faces opened | cut phases median / p95 (ms) | whole frame median / p95 / max (ms) | "
          "model update (median, ms) | step (median, ms) | CG iterations (median) |\n|---|---|---|---|---|---|---|---|---|\n";
    nlohmann::json j = {{"scene", "data/scenes/liver_incision.json"}, {"level", scene.object.levels}, {"machine", machine_description()},
                        {"runs", nlohmann::json::array()}};
    for (std::size_t k = 0; k < results.size(); ++k) {
        const CuttingRun& r = results[k];
        char line[512];
        std::snprintf(line, sizeof line, "| %zu | %s | %zu | %zu | %.2f / %.2f | %.1f / %.1f / %.1f | %.1f | %.1f | %.0f |\n",
                      k / configurations.size() + 1, r.preconditioner.c_str(), r.cutting_frames, r.faces, r.phases_p50, r.phases_p95,
                      r.whole_p50, r.whole_p95, r.whole_max, r.model_update_p50, r.step_p50, r.cg_p50);
        md << line;
        j["runs"].push_back({{"run", k / configurations.size() + 1}, {"preconditioner", r.preconditioner}, {"linear_solver", r.linear_solver},
                             {"cutting_frames", r.cutting_frames}, {"faces_opened", r.faces},
                             {"cut_phases_ms", {{"median", r.phases_p50}, {"p95", r.phases_p95}}},
                             {"whole_frame_ms", {{"median", r.whole_p50}, {"p95", r.whole_p95}, {"max", r.whole_max}}},
                             {"model_update_ms_median", r.model_update_p50}, {"step_ms_median", r.step_p50}, {"cg_iterations_median", r.cg_p50}});
    }
    md << "\nMedian over the runs of each run's p95 (range):";
    nlohmann::json summary = nlohmann::json::object();
    for (const auto& [name, s] : configurations) {
        std::vector<double> whole, phases;
        for (const CuttingRun& r : results)
            if (r.preconditioner == name) {
                whole.push_back(r.whole_p95);
                phases.push_back(r.phases_p95);
            }
        char text[256];
        std::snprintf(text, sizeof text, " %s: whole frame %.1f ms (%.1f - %.1f), cut phases %.2f ms (%.2f - %.2f);", name, quantile(whole, 0.5),
                      quantile(whole, 0.0), quantile(whole, 1.0), quantile(phases, 0.5), quantile(phases, 0.0), quantile(phases, 1.0));
        md << text;
        summary[name] = {{"whole_frame_p95_ms", {{"median", quantile(whole, 0.5)}, {"min", quantile(whole, 0.0)}, {"max", quantile(whole, 1.0)}}},
                         {"cut_phases_p95_ms", {{"median", quantile(phases, 0.5)}, {"min", quantile(phases, 0.0)}, {"max", quantile(phases, 1.0)}}}};
    }
    j["summary"] = summary;
    md << " targets 16.7 and 5 ms.\n";
    std::filesystem::create_directories(dir);
    write_atomically(dir / "cutting.md", [&](const std::filesystem::path& tmp) { std::ofstream(tmp) << md.str(); });
    write_atomically(dir / "cutting.json", [&](const std::filesystem::path& tmp) { std::ofstream(tmp) << j.dump(1) << '\n'; });
    std::printf("%s\nwrote %s and %s\n", md.str().c_str(), (dir / "cutting.md").c_str(), (dir / "cutting.json").c_str());
}

} // namespace vox::bench
