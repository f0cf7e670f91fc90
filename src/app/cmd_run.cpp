// voxsculpt run: a headless simulation of a scene. The tools move kinematically along the script,
// push the object by penalty contact, cut and wet it (app/tool_session.hpp); the object deforms
// under gravity, loads, constraints and the tools. Writes DIR/stats.json, DIR/final.obj and
// DIR/frame_NNNNN.obj.

#include "app/commands.hpp"
#include "core/atomic_file.hpp"
#include "core/error.hpp"
#include "core/log.hpp"
#include "core/progress.hpp"
#include "core/sample_stats.hpp"
#include "app/level_choice.hpp"
#include "app/scene_pictures.hpp"
#include "app/scene_simulation.hpp"
#include "app/device_run.hpp"
#include "app/isxfem_run.hpp"
#include "app/run_output.hpp"
#include "app/tool_session.hpp"
#include "cut/pieces.hpp"
#include "io/mesh_writer.hpp"
#include "io/scene.hpp"
#include "io/scene_object.hpp"
#include "surface/embedded_surface.hpp"

#include <CLI/CLI.hpp>
#include <nlohmann/json.hpp>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <optional>

namespace vox::app {
namespace {

/// Elements holding any water (scene regions or a wetting tool).
std::size_t wet_elements(const SceneSimulation& sim)
{
    std::size_t n = 0;
    for (std::uint32_t e = 0; e < sim.model().elements().size(); ++e) n += sim.solver().water(e) > 0.0;
    return n;
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
        std::string device, replay, record, tool;
        int render_every = 0;
        std::string camera = "iso", size = "960x720";
    };
    auto args = std::make_shared<Args>();
    CLI::App* cmd = app.add_subcommand("run", "Simulate a scene headless; write stats.json and the deformed surface");
    cmd->add_option("scene", args->scene, "Scene file (.json, see docs/scene-format.md)")->required();
    cmd->add_option("--frames", args->frames, "Number of frames (default: the script's duration / dt_s, else 100)")
        ->check(CLI::PositiveNumber);
    cmd->add_option("--out", args->out, "Output folder (default: the scene's output.dir)");
    cmd->add_option("--device", args->device, "Drive a tool by a device through the haptic loop (lockstep, 1 ms ticks): "
                                               "\"script\" follows the tool's script")
        ->check(CLI::IsMember({"script"}));
    cmd->add_option("--replay", args->replay, "Drive the tool by replaying this recording (docs/recording-format.md)");
    cmd->add_option("--record", args->record, "Record the device and the force sent at every tick to this file");
    cmd->add_option("--tool", args->tool, "The tool the device drives (default: the scene's first tool)");
    cmd->add_option("--render-every", args->render_every,
                    "Also draw DIR/frame_NNNNN.png every N frames and DIR/final.png, headless (offscreen OpenGL)")
        ->check(CLI::PositiveNumber);
    cmd->add_option("--camera", args->camera, "Camera of the pictures (see `voxsculpt render --help`; default iso)");
    cmd->add_option("--size", args->size, "Size of the pictures, WIDTHxHEIGHT (default 960x720)");
    cmd->callback([args] {
        const io::Scene scene = io::load_scene(args->scene);
        // Pictures only when asked for: no OpenGL context otherwise. Options checked up front.
        PictureOptions picture_options;
        picture_options.camera = render::parse_camera(args->camera);
        picture_options.camera.up = scene_up(scene);
        std::tie(picture_options.width, picture_options.height) = parse_size(args->size);
        if (scene.solver.type == io::SolverType::isxfem) {
            if (!args->device.empty() || !args->replay.empty())
                throw InputError("--device and --replay work with \"type\": \"dbg\" scenes only so far");
            std::unique_ptr<ScenePictures> pictures;
            if (args->render_every > 0) {
                pictures = std::make_unique<ScenePictures>(picture_options);
                log::info("pictures every {} frames ({} x {}, {})", args->render_every, picture_options.width, picture_options.height,
                          pictures->context_description());
            }
            run_isxfem(scene, args->scene, args->frames, args->out.empty() ? scene.output.dir : std::filesystem::path(args->out), pictures.get(),
                       args->render_every);
            return;
        }
        const grid::LabelGrid labels = io::load_scene_object(scene);
        // Coarser levels than the simulated one serve only the multigrid preconditioner (built
        // when the solver will use it: every level costs memory and time at each cut); "auto"
        // tries them all.
        const int simulated = std::max(scene.object.levels, 1);
        grid::BranchedGrid g = build_scene_grid(scene, labels, scene.object.auto_levels ? 6 : simulated);
        if (!scene.object.auto_levels && simulated < 6 && wants_multigrid(scene, g, scene.object.levels))
            g = build_scene_grid(scene, labels, std::min(6, simulated + 3));
        LevelChoice choice;
        choice.level = scene.object.levels;
        if (scene.object.auto_levels) {
            choice = choose_level(scene, g);
            log::info("levels auto: {}", choice.reason);
        }
        const int level = choice.level;
        SceneSimulation sim(scene, g, level);
        ToolSession tools(scene);
        if (!args->record.empty() && args->device.empty() && args->replay.empty())
            throw InputError("--record: there is no device to record; add --device script or --replay FILE");
        std::unique_ptr<DeviceRun> device;
        if (!args->device.empty() || !args->replay.empty()) {
            DeviceOptions o;
            o.tool = args->tool;
            if (!args->replay.empty()) o.replay = args->replay;
            device = std::make_unique<DeviceRun>(scene, tools, o);
            log::info("tool \"{}\" driven by the {} device through a virtual coupling (1 kHz, lockstep)", scene.tools[device->tool()].name,
                      device->device_name());
        }
        std::unique_ptr<ScenePictures> pictures;
        if (args->render_every > 0) {
            pictures = std::make_unique<ScenePictures>(picture_options);
            pictures->remember_uncut(sim);
            log::info("pictures every {} frames ({} x {}, {})", args->render_every, picture_options.width, picture_options.height,
                      pictures->context_description());
        }
        std::vector<ForceSample> tool_forces; // without a device: the first placed tool's, per frame
        // A cut rebuilds the model and solver: always reach them through `sim`.

        const double dt = scene.solver.dt_s;
        const double duration = scene.script.empty() ? 0.0 : scene.script.back().t_s;
        const int frames = args->frames.value_or(duration > 0 ? static_cast<int>(std::ceil(duration / dt)) : 100);
        const std::filesystem::path out = args->out.empty() ? scene.output.dir : std::filesystem::path(args->out);
        std::filesystem::create_directories(out);
        log::info("{}: level {}, {} elements, {} degrees of freedom, {} frames of {} s ({}; {}; {} mass{}{})", args->scene,
                  level, sim.model().elements().size(), sim.solver().dof_count(), frames, dt,
                  scene.solver.mode == io::SolverMode::static_equilibrium ? "quasi-static" : "implicit Euler",
                  sim.linear_solver(), scene.solver.lumped_mass ? "lumped" : "consistent",
                  sim.solver().has_plasticity() ? ", plastic" : "", scene.wet_regions.empty() ? "" : ", wetted regions");

        nlohmann::json stats{{"scene", args->scene},       {"level", level},
                             {"elements", sim.model().elements().size()}, {"dofs", sim.solver().dof_count()},
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
        std::size_t removed = 0, separated = 0;
        std::vector<double> cutting_ms; // frames that cut: collision + propagation + grid update + remesh
        fem::StepStats last;
        Progress progress("simulating", static_cast<std::uint64_t>(frames));
        for (int f = 1; f <= frames; ++f) {
            if (device) device->frame(sim, tools, (f - 1) * dt, dt);
            const ToolFrameStats tf = tools.frame(sim, g, f * dt, dt);
            removed += tf.removed_voxels;
            separated += tf.separated_faces;
            if (tf.removed_voxels + tf.separated_faces > 0) cutting_ms.push_back(tf.cutting_ms());
            if (tf.hold_object) { // a two-phase cut is being marked: the object is held, no step
                last.step_ms = last.assembly_ms = last.solve_ms = 0.0;
                last.cg_iterations = last.newton_iterations = last.substeps = 0;
                last.converged = true;
                last.energy_guarded = false;
            } else {
                last = sim.solver().step();
            }
            if (!device)
                for (const ToolFrame& t : tf.tools)
                    if (t.placed) {
                        tool_forces.push_back({f * dt, t.position_mm, t.force_n});
                        break;
                    }
            total_ms += last.step_ms;
            max_ms = std::max(max_ms, last.step_ms);
            converged += last.converged;
            if (last.energy_guarded) throw InputError(energy_guard_message(scene, f));
            if (!std::isfinite(last.elastic_energy_j) || !std::isfinite(last.kinetic_energy_j))
                throw InputError(args->scene + ": the simulation diverged at frame " + std::to_string(f) +
                                 " (non-finite energy); reduce solver.dt_s or check the materials");
            const nlohmann::json tool_frames = tool_frames_json(tf.tools);
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
                                       {"collision_ms", tf.collision_ms},
                                       {"propagation_ms", tf.propagation_ms},
                                       {"grid_update_ms", tf.grid_update_ms},
                                       {"remesh_ms", tf.remesh_ms},
                                       {"fem_update_ms", tf.fem_update_ms},
                                       {"removed_voxels", tf.removed_voxels},
                                       {"separated_faces", tf.separated_faces},
                                       {"separated_voxels", tf.separated_voxels},
                                       {"elements", sim.model().elements().size()},
                                       {"object_held", tf.hold_object},
                                       {"tools", tool_frames}});
            if (pictures && f % args->render_every == 0) pictures->write(out / frame_file_name(f, "png"), sim, tools, scene);
            if (f % scene.output.mesh_every_n_frames == 0) write_surface(out / frame_file_name(f, "obj"), sim);
            progress.update(static_cast<std::uint64_t>(f));
        }
        progress.finish();
        stats["summary"] = step_summary(frames, total_ms, max_ms, converged);
        stats["summary"].update(
            {{"removed_voxels", removed},
             {"separated_faces", separated},
             {"separated_voxels", tools.separated_voxels()},
             {"voxels", g.voxels().alive_count()},
             {"cutting_frames", cutting_ms.size()},
             {"cutting_ms_p95", quantile(cutting_ms, 0.95)},
             {"final_elements", sim.model().elements().size()},
             {"pieces", cut::piece_count(sim.model())},
             {"wet_elements", wet_elements(sim)},
             {"mass_kg", g.total_mass_kg()},
             {"final_max_displacement_mm", last.max_displacement_m * 1e3},
             {"final_elastic_energy_j", last.elastic_energy_j},
             {"final_kinetic_energy_j", last.kinetic_energy_j}});
        if (!sim.solver().fallback_note().empty()) {
            log::warn("{}", sim.solver().fallback_note());
            stats["linear_solver"] = sim.solver().fallback_note();
        }
        write_surface(out / "final.obj", sim);
        if (pictures) pictures->write(out / "final.png", sim, tools, scene);
        if (device) {
            write_forces(out, device->forces(), "force on the device, " + scene.tools[device->tool()].name);
            if (!args->record.empty()) haptics::write_recording(args->record, device->recording());
        } else if (!tool_forces.empty()) {
            write_forces(out, tool_forces, "contact force on the tool");
        }
        write_atomically(out / "stats.json", [&](const std::filesystem::path& tmp) {
            std::ofstream(tmp) << stats.dump(1) << '\n';
        });
        log::info("wrote {}: stats.json, final.obj and {} frame meshes; mean step {:.2f} ms, max displacement {:.3f} mm",
                  out.string(), frames / scene.output.mesh_every_n_frames, total_ms / std::max(frames, 1),
                  last.max_displacement_m * 1e3);
    });
}

} // namespace vox::app
