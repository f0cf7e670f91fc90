// voxsculpt bench compare: the same scene and tool script by the branched grid and by Is-XFEM
// (k = 0.1, and k = 0: standard XFEM), side by side. Every column is computed by the same code for
// every method, from what the one frame loop reports (sim/frame_loop.hpp) and what every method
// gives (sim/method.hpp): the whole frame and each phase with the same boundaries, the volume
// enclosed by the closed surface before and after, the final surfaces compared vertex by vertex.

#include "bench/harness/compare.hpp"

#include "core/atomic_file.hpp"
#include "core/error.hpp"
#include "core/log.hpp"
#include "core/sample_stats.hpp"
#include "core/stopwatch.hpp"
#include "io/scene_object.hpp"
#include "sim/frame_loop.hpp"
#include "sim/method_factory.hpp"

#include <nlohmann/json.hpp>

#include <cmath>
#include <cstdio>
#include <fstream>
#include <map>
#include <sstream>

namespace vox::bench {
namespace {

/// One method's run of the scene.
struct Run {
    std::string method;
    std::size_t dofs_start = 0, dofs_end = 0;
    std::vector<double> frame_ms, step_ms, cut_ms; ///< cut_ms: frames that cut (propagation, grid update, remesh, model update)
    std::vector<double> iterations;
    int converged = 0, frames = 0, held = 0;
    double volume_before_mm3 = 0.0, volume_after_mm3 = 0.0;
    std::size_t triangles = 0, pieces = 0;
    bool finite = true;
    std::map<std::uint64_t, Eigen::Vector3d> displacement_mm; ///< surface vertex key -> final displacement
};

Run run_method(io::Scene scene, const std::shared_ptr<const grid::LabelGrid>& labels, int frames, io::SolverType type, double k)
{
    io::use_method(scene, type);
    scene.solver.isxfem_k = k;
    std::unique_ptr<sim::Method> method = sim::open_method(scene, labels).method;
    sim::ToolPolicy tools(scene);
    sim::FrameLoop loop(scene, *method, tools);
    Run r;
    char name[48];
    if (type == io::SolverType::dbg) std::snprintf(name, sizeof name, "dbg");
    else if (type == io::SolverType::shape_matching) std::snprintf(name, sizeof name, "shape matching");
    else std::snprintf(name, sizeof name, k > 0.0 ? "Is-XFEM (k = %g)" : "XFEM (k = %g)", k);
    r.method = name;
    r.frames = frames;
    r.dofs_start = method->dof_count();
    r.volume_before_mm3 = sim::enclosed_volume_mm3(method->surface_mesh());
    for (int f = 1; f <= frames; ++f) {
        Stopwatch clock;
        sim::FrameStats s;
        try {
            s = loop.next();
        } catch (const InputError& e) { // diverged: said in the table
            log::warn("{}: {}", r.method, e.what());
            r.finite = false;
            break;
        }
        r.frame_ms.push_back(clock.lap());
        const sim::CutFigures& c = s.tools.cut;
        if (c.changed()) r.cut_ms.push_back(s.tools.propagation_ms + c.grid_update_ms + c.remesh_ms + c.fem_update_ms);
        if (s.tools.hold_object) {
            ++r.held;
            continue;
        }
        r.step_ms.push_back(s.step.step_ms);
        r.iterations.push_back(s.step.cg_iterations);
        r.converged += s.step.converged;
    }
    r.dofs_end = method->dof_count();
    const surface::SurfaceMesh final_surface = method->surface_mesh();
    r.volume_after_mm3 = sim::enclosed_volume_mm3(final_surface);
    r.triangles = final_surface.triangles.size();
    r.pieces = method->piece_count();
    const std::vector<Eigen::Vector3d> u = method->surface_displacements_mm();
    const std::vector<std::uint64_t> keys = method->surface_keys();
    for (std::size_t i = 0; i < keys.size(); ++i) r.displacement_mm[keys[i]] = u[i];
    return r;
}

std::string format_ms(double ms)
{
    char text[32];
    std::snprintf(text, sizeof text, "%.2f", ms);
    return text;
}

double median(const std::vector<double>& v) { return v.empty() ? 0.0 : quantile(v, 0.5); }
double maximum(const std::vector<double>& v) { return v.empty() ? 0.0 : quantile(v, 1.0); }

} // namespace

void run_compare(const std::string& scene_path, std::optional<int> frame_count, const std::filesystem::path& out)
{
    io::Scene scene = io::load_scene(scene_path);
    if (scene.object.auto_levels) throw scene.error("object.levels", "bench compare needs a fixed level (0 to 6), not \"auto\"");
    // Both methods cut the same way: separating (the one both have) where the scene leaves it open.
    for (std::size_t t = 0; t < scene.tools.size(); ++t) {
        if (scene.tools[t].action != io::ToolAction::cut) continue;
        if (scene.tools[t].cut_mode_given && scene.tools[t].cut_mode == io::CutMode::remove)
            throw scene.error("tools[" + std::to_string(t) + "].cut_mode",
                              "\"remove\": Is-XFEM cannot remove material, so the methods cannot be compared on this cut; use \"separate\"");
        scene.tools[t].cut_mode = io::CutMode::separate;
        scene.tools[t].cut_mode_given = true;
    }
    auto labels = std::make_shared<const grid::LabelGrid>(io::load_scene_object(scene));
    const double dt = scene.solver.dt_s;
    const double duration = scene.script.empty() ? 0.0 : scene.script.back().t_s;
    const int frames = frame_count.value_or(duration > 0 ? static_cast<int>(std::ceil(duration / dt)) : 100);
    log::info("{}: {} frames of {} s at level {}, dbg, Is-XFEM (k = 0.1), XFEM (k = 0), then shape matching", scene_path, frames, dt,
              scene.object.levels);
    std::vector<Run> runs;
    runs.push_back(run_method(scene, labels, frames, io::SolverType::dbg, scene.solver.isxfem_k));
    runs.push_back(run_method(scene, labels, frames, io::SolverType::isxfem, 0.1));
    runs.push_back(run_method(scene, labels, frames, io::SolverType::isxfem, 0.0));
    runs.push_back(run_method(scene, labels, frames, io::SolverType::shape_matching, scene.solver.isxfem_k));

    std::ostringstream md;
    md << "# " << scene_path << ": dbg against Is-XFEM and shape matching (`voxsculpt bench compare`)\n\n"
       << frames << " frames of " << dt << " s at level " << scene.object.levels
       << ", the same tool script and tool policy, cutting tools separating; one run each, machine: " << machine_description()
       << "; times in ms. A frame is the tools (contact, cut, closure) and the step; a cut update is what a cutting frame "
          "spends on the cut itself (propagation, grid update, remesh or closure, model update); volumes are enclosed by "
          "the closed surface.\n\n"
          "| method | DOFs (start - end) | frame median | frame max | step median | CG (shape matching: its) iterations (median) | converged steps | "
          "frames held | frames that cut | cut update p95 | volume before - after (mm^3) | surface triangles | pieces |\n"
          "|---|---|---|---|---|---|---|---|---|---|---|---|---|\n";
    char line[640];
    for (const Run& r : runs) {
        std::snprintf(line, sizeof line, "| %s | %zu - %zu | %.2f | %.2f | %.2f | %.0f | %d of %zu%s | %d | %zu | %s | %.1f - %.1f | %zu | %zu |\n",
                      r.method.c_str(), r.dofs_start, r.dofs_end, median(r.frame_ms), maximum(r.frame_ms), median(r.step_ms),
                      median(r.iterations), r.converged, r.step_ms.size(), r.finite ? "" : " (diverged)", r.held, r.cut_ms.size(),
                      r.cut_ms.empty() ? "n/a (no cut)" : format_ms(quantile(r.cut_ms, 0.95)).c_str(),
                      r.volume_before_mm3, r.volume_after_mm3, r.triangles, r.pieces);
        md << line;
    }
    // Final surfaces: the vertices both methods still have.
    md << "\nFinal surface displacement against dbg (vertices present in both):\n\n"
          "| method | vertices compared | RMS displacement, dbg (mm) | RMS difference (mm) | max difference (mm) |\n|---|---|---|---|---|\n";
    for (std::size_t m = 1; m < runs.size(); ++m) {
        double sum_d = 0.0, sum_u = 0.0, worst = 0.0;
        std::size_t n = 0;
        for (const auto& [key, u] : runs[0].displacement_mm) {
            const auto it = runs[m].displacement_mm.find(key);
            if (it == runs[m].displacement_mm.end()) continue;
            const double d = (it->second - u).norm();
            sum_d += d * d;
            sum_u += u.squaredNorm();
            worst = std::max(worst, d);
            ++n;
        }
        std::snprintf(line, sizeof line, "| %s | %zu | %.3f | %.3f | %.3f |\n", runs[m].method.c_str(), n, n ? std::sqrt(sum_u / n) : 0.0,
                      n ? std::sqrt(sum_d / n) : 0.0, worst);
        md << line;
    }
    // The same figures as data, for scripts and for rendering tables elsewhere.
    nlohmann::json data{{"scene", scene_path}, {"frames", frames}, {"dt_s", dt}, {"level", scene.object.levels},
                        {"machine", machine_description()}, {"methods", nlohmann::json::array()}};
    for (const Run& r : runs)
        data["methods"].push_back({{"method", r.method},
                                   {"dofs_start", r.dofs_start},
                                   {"dofs_end", r.dofs_end},
                                   {"frame_ms", r.frame_ms},
                                   {"step_ms", r.step_ms},
                                   {"cut_update_ms", r.cut_ms},
                                   {"cg_iterations", r.iterations},
                                   {"converged_steps", r.converged},
                                   {"frames_held", r.held},
                                   {"diverged", !r.finite},
                                   {"volume_before_mm3", r.volume_before_mm3},
                                   {"volume_after_mm3", r.volume_after_mm3},
                                   {"surface_triangles", r.triangles},
                                   {"pieces", r.pieces}});
    std::filesystem::create_directories(out);
    const std::string stem = "compare-" + std::filesystem::path(scene_path).stem().string();
    write_atomically(out / (stem + ".md"), [&](const std::filesystem::path& tmp) { std::ofstream(tmp) << md.str(); });
    write_atomically(out / (stem + ".json"), [&](const std::filesystem::path& tmp) { std::ofstream(tmp) << data.dump(1) << '\n'; });
    std::printf("%s\nwrote %s and %s\n", md.str().c_str(), (out / (stem + ".md")).c_str(), (out / (stem + ".json")).c_str());
}

} // namespace vox::bench
