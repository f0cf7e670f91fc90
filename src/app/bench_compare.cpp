#include "app/bench_compare.hpp"

#include "app/isxfem_tools.hpp"
#include "app/isxfem_simulation.hpp"
#include "app/scene_simulation.hpp"
#include "app/tool_session.hpp"
#include "core/atomic_file.hpp"
#include "core/log.hpp"
#include "core/sample_stats.hpp"
#include "io/scene_object.hpp"

#include <chrono>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <map>
#include <sstream>

namespace vox::app {
namespace {

/// One method's run of the scene.
struct Run {
    std::string method;
    std::size_t dofs_start = 0, dofs_end = 0;
    std::vector<double> step_ms, cut_ms; ///< cut_ms: frames that cut
    std::vector<double> iterations;
    int converged = 0, frames = 0;
    double volume_lost_mm3 = 0.0;
    std::size_t triangles = 0;
    bool finite = true;
    std::map<std::uint64_t, Eigen::Vector3d> displacement_mm; ///< surface vertex key -> final displacement
};

double ms_since(std::chrono::steady_clock::time_point t)
{
    return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t).count();
}

Run run_dbg(io::Scene scene, const grid::LabelGrid& labels, int frames)
{
    scene.solver.type = io::SolverType::dbg;
    const int level = scene.object.levels;
    const int simulated = std::max(level, 1);
    grid::BranchedGrid g = build_scene_grid(scene, labels, simulated);
    if (simulated < 6 && wants_multigrid(scene, g, level)) g = build_scene_grid(scene, labels, std::min(6, simulated + 3));
    SceneSimulation sim(scene, g, level);
    ToolSession tools(scene);
    Run r;
    r.method = "dbg";
    r.frames = frames;
    r.dofs_start = sim.solver().dof_count();
    const double dt = scene.solver.dt_s;
    const Eigen::Vector3d voxel_mm = g.voxels().voxel_size_m() * 1e3;
    for (int f = 1; f <= frames; ++f) {
        const ToolFrameStats tf = tools.frame(sim, g, f * dt, dt);
        if (tf.removed_voxels + tf.separated_faces > 0) r.cut_ms.push_back(tf.cutting_ms() + tf.fem_update_ms);
        r.volume_lost_mm3 += static_cast<double>(tf.removed_voxels) * voxel_mm.prod();
        if (tf.hold_object) continue;
        const fem::StepStats s = sim.solver().step();
        r.step_ms.push_back(s.step_ms);
        r.iterations.push_back(s.cg_iterations);
        r.converged += s.converged;
        r.finite = r.finite && std::isfinite(s.kinetic_energy_j) && std::isfinite(s.elastic_energy_j);
    }
    r.dofs_end = sim.solver().dof_count();
    r.triangles = sim.surface().embedded().triangle_count();
    const std::vector<Eigen::Vector3d> u = sim.surface().displacements(sim.solver().positions());
    const auto& vertices = sim.surface().embedded().vertices();
    for (std::size_t i = 0; i < vertices.size(); ++i)
        if (vertices[i].users) r.displacement_mm[vertices[i].key] = 1e3 * u[i];
    return r;
}

Run run_isxfem_k(io::Scene scene, const grid::LabelGrid& labels, int frames, double k)
{
    scene.solver.type = io::SolverType::isxfem;
    scene.solver.isxfem_k = k;
    const int level = scene.object.levels;
    const grid::BranchedGrid g = build_scene_grid(scene, labels, std::max(level, 1));
    IsxfemSimulation sim(scene, g, level);
    IsxfemTools tools(scene);
    Run r;
    char name[48];
    std::snprintf(name, sizeof name, k > 0.0 ? "Is-XFEM (k = %g)" : "XFEM (k = %g)", k);
    r.method = name;
    r.frames = frames;
    r.dofs_start = sim.solver().dof_count();
    const double dt = scene.solver.dt_s;
    for (int f = 1; f <= frames; ++f) {
        const auto t = std::chrono::steady_clock::now();
        const IsxfemToolFrame tf = tools.frame(sim, f, dt);
        if (tf.cut.cut_tets > 0) r.cut_ms.push_back(ms_since(t));
        if (tf.hold_object) continue;
        const isxfem::XfemStepStats s = sim.solver().step();
        r.step_ms.push_back(s.step_ms);
        r.iterations.push_back(s.cg_iterations);
        r.converged += s.converged;
        r.finite = r.finite && std::isfinite(s.kinetic_energy_j);
        if (!r.finite) break;
    }
    r.dofs_end = sim.solver().dof_count();
    r.triangles = sim.surface_mesh().triangles.size();
    const std::vector<Eigen::Vector3d> u = sim.surface_displacements();
    const std::vector<std::uint64_t> keys = sim.surface_keys();
    for (std::size_t i = 0; i < keys.size(); ++i) r.displacement_mm[keys[i]] = 1e3 * u[i];
    return r;
}

double median(std::vector<double> v) { return v.empty() ? 0.0 : quantile(std::move(v), 0.5); }

} // namespace

void run_compare(const std::string& scene_path, std::optional<int> frame_count, const std::filesystem::path& out)
{
    const io::Scene scene = io::load_scene(scene_path);
    if (scene.object.auto_levels) throw scene.error("object.levels", "bench compare needs a fixed level (0 to 6), not \"auto\"");
    const grid::LabelGrid labels = io::load_scene_object(scene);
    const double dt = scene.solver.dt_s;
    const double duration = scene.script.empty() ? 0.0 : scene.script.back().t_s;
    const int frames = frame_count.value_or(duration > 0 ? static_cast<int>(std::ceil(duration / dt)) : 100);
    log::info("{}: {} frames of {} s at level {}, dbg then Is-XFEM (k = 0.1) then XFEM (k = 0)", scene_path, frames, dt,
              scene.object.levels);
    std::vector<Run> runs;
    runs.push_back(run_dbg(scene, labels, frames));
    runs.push_back(run_isxfem_k(scene, labels, frames, 0.1));
    runs.push_back(run_isxfem_k(scene, labels, frames, 0.0));

    std::ostringstream md;
    md << "# " << scene_path << ": dbg against Is-XFEM (`voxsculpt bench compare`)\n\n"
       << frames << " frames of " << dt << " s at level " << scene.object.levels
       << ", the same tool script; one run each, one machine, times in ms.\n\n"
          "| method | DOFs (start - end) | step median | step max | CG iterations (median) | converged frames | frames that cut | "
          "cut update p95 | volume lost (mm^3) | surface triangles |\n"
          "|---|---|---|---|---|---|---|---|---|---|\n";
    char line[512];
    for (const Run& r : runs) {
        std::snprintf(line, sizeof line, "| %s | %zu - %zu | %.2f | %.2f | %.0f | %d of %zu%s | %zu | %.2f | %.1f | %zu |\n", r.method.c_str(),
                      r.dofs_start, r.dofs_end, median(r.step_ms), r.step_ms.empty() ? 0.0 : *std::max_element(r.step_ms.begin(), r.step_ms.end()),
                      median(r.iterations), r.converged, r.step_ms.size(), r.finite ? "" : " (diverged)", r.cut_ms.size(),
                      r.cut_ms.empty() ? 0.0 : quantile(r.cut_ms, 0.95), r.volume_lost_mm3, r.triangles);
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
    std::filesystem::create_directories(out);
    const std::filesystem::path file = out / ("compare-" + std::filesystem::path(scene_path).stem().string() + ".md");
    write_atomically(file, [&](const std::filesystem::path& tmp) { std::ofstream(tmp) << md.str(); });
    std::printf("%s\nwrote %s\n", md.str().c_str(), file.c_str());
}

} // namespace vox::app
