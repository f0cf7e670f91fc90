// voxsculpt run: a headless simulation of a scene. The tools move kinematically along the script
// (contact and cutting come with the cutting module); the object deforms under gravity, loads and
// constraints. Writes DIR/stats.json, DIR/final.obj and DIR/frame_NNNNN.obj.

#include "app/commands.hpp"
#include "core/atomic_file.hpp"
#include "core/error.hpp"
#include "core/log.hpp"
#include "core/progress.hpp"
#include "app/level_choice.hpp"
#include "app/scene_simulation.hpp"
#include "io/mesh_writer.hpp"
#include "io/scene.hpp"
#include "io/scene_object.hpp"
#include "surface/embedded_surface.hpp"

#include <CLI/CLI.hpp>
#include <nlohmann/json.hpp>

#include <cmath>
#include <cstdio>
#include <fstream>
#include <optional>

namespace vox::app {
namespace {

/// Where each tool is at time t (linear between its script entries; before the first and after
/// the last it stays put), world mm.
std::vector<Eigen::Vector3d> tool_positions(const io::Scene& scene, double t)
{
    std::vector<Eigen::Vector3d> out(scene.tools.size(), Eigen::Vector3d::Constant(std::nan("")));
    for (std::size_t k = 0; k < scene.tools.size(); ++k) {
        const io::ScriptEntry* before = nullptr;
        const io::ScriptEntry* after = nullptr;
        for (const io::ScriptEntry& e : scene.script) {
            if (e.tool_index != k) continue;
            if (e.t_s <= t) before = &e;
            if (e.t_s >= t && !after) after = &e;
        }
        if (before && after && after->t_s > before->t_s) {
            const double a = (t - before->t_s) / (after->t_s - before->t_s);
            out[k] = (1 - a) * before->position_mm + a * after->position_mm;
        } else if (before || after) {
            out[k] = (before ? before : after)->position_mm;
        }
    }
    return out;
}

void write_surface(const std::filesystem::path& path, const SceneSimulation& sim)
{
    const surface::SurfaceMesh m = sim.surface().mesh(sim.solver().positions());
    io::write_mesh(path.string(), m.positions, m.triangles, m.labels);
}

} // namespace

void add_run_command(CLI::App& app)
{
    struct Args {
        std::string scene;
        std::optional<int> frames;
        std::string out;
    };
    auto args = std::make_shared<Args>();
    CLI::App* cmd = app.add_subcommand("run", "Simulate a scene headless; write stats.json and the deformed surface");
    cmd->add_option("scene", args->scene, "Scene file (.json, see docs/scene-format.md)")->required();
    cmd->add_option("--frames", args->frames, "Number of frames (default: the script's duration / dt_s, else 100)")
        ->check(CLI::PositiveNumber);
    cmd->add_option("--out", args->out, "Output folder (default: the scene's output.dir)");
    cmd->callback([args] {
        const io::Scene scene = io::load_scene(args->scene);
        if (scene.solver.type != io::SolverType::dbg)
            throw scene.error("solver.type", "\"isxfem\" runs are not available yet; use \"dbg\"");
        const grid::LabelGrid labels = io::load_scene_object(scene);
        // Coarser levels than the simulated one serve the multigrid preconditioner; "auto" tries them all.
        const int max_level = scene.object.auto_levels ? 6 : std::min(6, std::max(scene.object.levels, 1) + 3);
        const grid::BranchedGrid g = build_scene_grid(scene, labels, max_level);
        LevelChoice choice;
        choice.level = scene.object.levels;
        if (scene.object.auto_levels) {
            choice = choose_level(scene, g);
            log::info("levels auto: {}", choice.reason);
        }
        const int level = choice.level;
        SceneSimulation sim(scene, g, level);
        fem::ImplicitSolver& solver = sim.solver();
        const fem::HexModel& model = sim.model();

        const double dt = scene.solver.dt_s;
        const double duration = scene.script.empty() ? 0.0 : scene.script.back().t_s;
        const int frames = args->frames.value_or(duration > 0 ? static_cast<int>(std::ceil(duration / dt)) : 100);
        const std::filesystem::path out = args->out.empty() ? scene.output.dir : std::filesystem::path(args->out);
        std::filesystem::create_directories(out);
        log::info("{}: level {}, {} elements, {} degrees of freedom, {} frames of {} s ({}; {}; {} mass{}{})", args->scene,
                  level, model.elements().size(), solver.dof_count(), frames, dt,
                  scene.solver.mode == io::SolverMode::static_equilibrium ? "quasi-static" : "implicit Euler",
                  sim.linear_solver(), scene.solver.lumped_mass ? "lumped" : "consistent",
                  solver.has_plasticity() ? ", plastic" : "", scene.wet_regions.empty() ? "" : ", wetted regions");

        nlohmann::json stats{{"scene", args->scene},       {"level", level},
                             {"elements", model.elements().size()}, {"dofs", solver.dof_count()},
                             {"dt_s", dt},                  {"linear_solver", sim.linear_solver()},
                             {"frames", nlohmann::json::array()}};
        if (scene.object.auto_levels) {
            nlohmann::json trials = nlohmann::json::array();
            for (const LevelTrial& t : choice.trials) {
                nlohmann::json j{{"level", t.level}, {"dofs", t.dofs}};
                if (t.error >= 0.0) j["error"] = t.error;
                else j["step_ms"] = t.step_ms;
                trials.push_back(j);
            }
            stats["level_choice"] = {{"reason", choice.reason}, {"trials", trials}};
        }
        double total_ms = 0.0, max_ms = 0.0;
        int converged = 0;
        fem::StepStats last;
        Progress progress("simulating", static_cast<std::uint64_t>(frames));
        for (int f = 1; f <= frames; ++f) {
            last = solver.step();
            total_ms += last.step_ms;
            max_ms = std::max(max_ms, last.step_ms);
            converged += last.converged;
            if (last.energy_guarded) throw InputError(energy_guard_message(scene, f));
            if (!std::isfinite(last.elastic_energy_j) || !std::isfinite(last.kinetic_energy_j))
                throw InputError(args->scene + ": the simulation diverged at frame " + std::to_string(f) +
                                 " (non-finite energy); reduce solver.dt_s or check the materials");
            nlohmann::json tools = nlohmann::json::array();
            for (const Eigen::Vector3d& p : tool_positions(scene, f * dt))
                tools.push_back(p.allFinite() ? nlohmann::json{p.x(), p.y(), p.z()} : nlohmann::json(nullptr));
            stats["frames"].push_back({{"frame", f},
                                       {"t_s", f * dt},
                                       {"step_ms", last.step_ms},
                                       {"assembly_ms", last.assembly_ms},
                                       {"solve_ms", last.solve_ms},
                                       {"cg_iterations", last.cg_iterations},
                                       {"newton_iterations", last.newton_iterations},
                                       {"residual", last.residual},
                                       {"converged", last.converged},
                                       {"substeps", last.substeps},
                                       {"kinetic_energy_j", last.kinetic_energy_j},
                                       {"elastic_energy_j", last.elastic_energy_j},
                                       {"max_displacement_mm", last.max_displacement_m * 1e3},
                                       {"tool_positions_mm", tools}});
            if (f % scene.output.mesh_every_n_frames == 0) {
                char name[32];
                std::snprintf(name, sizeof name, "frame_%05d.obj", f);
                write_surface(out / name, sim);
            }
            progress.update(static_cast<std::uint64_t>(f));
        }
        progress.finish();
        stats["summary"] = {{"frames", frames},
                            {"total_step_ms", total_ms},
                            {"mean_step_ms", frames ? total_ms / frames : 0.0},
                            {"max_step_ms", max_ms},
                            {"converged_frames", converged},
                            {"final_max_displacement_mm", last.max_displacement_m * 1e3},
                            {"final_elastic_energy_j", last.elastic_energy_j},
                            {"final_kinetic_energy_j", last.kinetic_energy_j}};
        if (!solver.fallback_note().empty()) {
            log::warn("{}", solver.fallback_note());
            stats["linear_solver"] = solver.fallback_note();
        }
        write_surface(out / "final.obj", sim);
        write_atomically(out / "stats.json", [&](const std::filesystem::path& tmp) {
            std::ofstream(tmp) << stats.dump(1) << '\n';
        });
        log::info("wrote {}: stats.json, final.obj and {} frame meshes; mean step {:.2f} ms, max displacement {:.3f} mm",
                  out.string(), frames / scene.output.mesh_every_n_frames, total_ms / std::max(frames, 1),
                  last.max_displacement_m * 1e3);
    });
}

} // namespace vox::app
