// voxsculpt run: a headless simulation of a scene with its method (`solver.type`). The tools move
// along the script (or a device drives one through the haptic loop), push the object by penalty
// contact, cut and wet it; the object deforms under gravity, loads, constraints and the tools, one
// frame at a time through the frame loop every command shares (sim/frame_loop.hpp). Writes
// DIR/stats.json (sim/run_record.hpp), DIR/final.obj and DIR/frame_NNNNN.obj, and with
// --render-every pictures: all into a staging folder moved into DIR when the run completes, so
// a run that fails leaves nothing behind.

#include "app/commands.hpp"
#include "render/draw_mesh.hpp"
#include "core/label_palette.hpp"
#include "view/scene_pictures.hpp"
#include "core/atomic_file.hpp"
#include "core/error.hpp"
#include "core/log.hpp"
#include "core/progress.hpp"
#include "core/staging_dir.hpp"
#include "io/glb_writer.hpp"
#include "io/label_map_writer.hpp"
#include "io/mesh_writer.hpp"
#include "io/vtu_writer.hpp"
#include "io/scene.hpp"
#include "io/scene_object.hpp"
#include "sim/device_run.hpp"
#include "sim/journal.hpp"
#include "sim/frame_loop.hpp"
#include "sim/level_governor.hpp"
#include "sim/method_factory.hpp"
#include "sim/run_record.hpp"

#include <CLI/CLI.hpp>
#include <nlohmann/json.hpp>
#include <tbb/global_control.h>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <optional>
#include <thread>

namespace vox::app {

using view::PictureOptions;
using view::ScenePictures;
using view::parse_size;
using view::scene_up;
namespace {

void write_surface(const std::filesystem::path& path, const sim::Method& method)
{
    const surface::SurfaceMesh m = method.surface_mesh();
    io::write_mesh(path.string(), m.positions, m.triangles, m.labels);
}

nlohmann::json level_choice_json(const sim::LevelChoice& choice)
{
    nlohmann::json trials = nlohmann::json::array();
    for (const sim::LevelTrial& t : choice.trials) {
        nlohmann::json j{{"level", t.level}, {"dofs", t.dofs}};
        if (t.error >= 0.0) {
            j["error"] = t.error;
        } else {
            j["frame_ms"] = t.frame_ms;
            j["step_ms"] = t.step_ms;
            j["preconditioner"] = std::string(io::preconditioner_name(t.preconditioner));
        }
        trials.push_back(j);
    }
    return {{"reason", choice.reason}, {"trials", trials}};
}

} // namespace

void add_run_command(CLI::App& app)
{
    struct Args {
        std::string scene;
        std::optional<int> frames;
        std::string out;
        std::vector<std::string> devices, tools;
        std::string replay, record, resume;
        int render_every = 0;
        std::string camera = "iso", size = "960x720";
        bool cage = false;
        std::string solver;
    };
    auto args = std::make_shared<Args>();
    CLI::App* cmd = app.add_subcommand("run", "Simulate a scene headless; write stats.json and the deformed surface");
    cmd->add_option("scene", args->scene, "Scene file (.json, see docs/scene-format.md)")->required();
    cmd->add_option("--frames", args->frames, "Number of frames (default: the script's duration / dt_s, else 100)")
        ->check(CLI::PositiveNumber);
    cmd->add_option("--out", args->out, "Output folder (default: the scene's output.dir)");
    cmd->add_option("--device", args->devices,
                    "Drive a tool by a device through the haptic loop: \"script\" follows the tool's script (lockstep, 1 ms ticks); "
                    "\"openhaptics\" or \"forcedimension\", a force-feedback device through its vendor's library (real time: the loop at "
                    "1 kHz of wall clock, frames paced to it; docs/devices.md). Once per device, each with its --tool")
        ->check(CLI::IsMember({"script", "openhaptics", "forcedimension"}))
        ->allow_extra_args(false);
    cmd->add_option("--replay", args->replay, "Drive the tools by replaying this recording, every device in it (docs/recording-format.md)");
    cmd->add_option("--record", args->record, "Record every device and the force sent to it at every tick to this file");
    cmd->add_option("--tool", args->tools, "The tool a device drives, once per --device in the same order (default, one device: the scene's first tool)")
        ->allow_extra_args(false);
    cmd->add_option("--resume", args->resume,
                    "Start from the last stroke of this session journal (a device run writes OUT.journal; docs/journal.md)");
    cmd->add_option("--solver", args->solver, "Simulate with this method instead of the scene's solver.type: dbg, isxfem or shape_matching")
        ->check(CLI::IsMember({"dbg", "isxfem", "shape_matching"}));
    cmd->add_option("--render-every", args->render_every,
                    "Also draw DIR/frame_NNNNN.png every N frames and DIR/final.png, headless (offscreen OpenGL)")
        ->check(CLI::PositiveNumber);
    cmd->add_option("--camera", args->camera, "Camera of the pictures (see `voxsculpt render --help`; default iso)");
    cmd->add_option("--size", args->size, "Size of the pictures, WIDTHxHEIGHT (default 960x720)");
    cmd->add_flag("--cage", args->cage,
                  "Draw the branched grid's element cage in the pictures, through a translucent surface (two levels: fine in orange, "
                  "coarse in dark blue, border nodes tied to the coarse side in green)");
    cmd->callback([args] {
        io::Scene scene = io::load_scene(args->scene);
        if (!args->solver.empty()) io::use_method(scene, io::solver_type_named(args->solver));
        // Options checked up front; pictures only when asked for (no OpenGL context otherwise).
        PictureOptions picture_options;
        picture_options.camera = render::parse_camera(args->camera);
        picture_options.camera.up = scene_up(scene);
        picture_options.cage = args->cage;
        std::tie(picture_options.width, picture_options.height) = parse_size(args->size);
        if (!args->record.empty() && args->devices.empty() && args->replay.empty())
            throw InputError("--record: there is no device to record; add --device script or --replay FILE");
        if (!args->replay.empty() && !args->devices.empty())
            throw InputError("--replay and --device: a replay drives the tools with the devices it recorded; give one or the other");
        const std::size_t device_count = args->replay.empty() ? args->devices.size() : 1;
        if (device_count > 1 ? args->tools.size() != device_count : args->tools.size() > 1)
            throw InputError("--tool: give one per --device, in the same order (" + std::to_string(args->devices.size()) + " device(s), " +
                             std::to_string(args->tools.size()) + " tool(s))");
        if (!args->resume.empty() && !std::filesystem::is_regular_file(args->resume)) // before the object is loaded
            throw file_error(args->resume, "no such file (--resume takes a session journal)");

        // The devices first: one that cannot be opened is said before the object loads.
        sim::ToolPolicy tools(scene);
        std::unique_ptr<sim::DeviceRun> device;
        if (!args->devices.empty() || !args->replay.empty()) {
            sim::DeviceOptions o;
            o.devices = args->devices;
            o.tools = args->tools;
            if (!args->replay.empty()) o.replay = args->replay;
            device = std::make_unique<sim::DeviceRun>(scene, tools, o);
            for (std::size_t i = 0; i < device->device_count(); ++i)
                log::info("tool \"{}\" driven by the {} device through a virtual coupling (1 kHz, {})", scene.tools[device->tool(i)].name,
                          device->device_name(i), device->live() ? "real time" : "lockstep");
        }
        // A live run: the simulation keeps to one core, the haptic loop has the other.
        std::optional<tbb::global_control> one_thread;
        if (device && device->live()) one_thread.emplace(tbb::global_control::max_allowed_parallelism, 1);
        auto labels = std::make_shared<const grid::LabelGrid>(io::load_scene_object(scene));
        const sim::OpenedMethod opened = sim::open_method(scene, labels);
        sim::Method& method = *opened.method;
        std::unique_ptr<ScenePictures> pictures;
        if (args->render_every > 0) {
            pictures = std::make_unique<ScenePictures>(picture_options);
            log::info("pictures every {} frames ({} x {}, {})", args->render_every, picture_options.width, picture_options.height,
                      pictures->context_description());
        }

        const double dt = scene.solver.dt_s;
        const double duration = scene.script.empty() ? 0.0 : scene.script.back().t_s;
        const int frames = args->frames.value_or(duration > 0 ? static_cast<int>(std::ceil(duration / dt)) : 100);
        const std::filesystem::path out = args->out.empty() ? scene.output.dir : std::filesystem::path(args->out);
        // A resumed run starts where its journal's last stroke ended, the object cut as it was then.
        sim::JournalHeader header = sim::journal_header(args->scene, method);
        header.any_level = scene.object.auto_levels; // the run may have moved between levels
        int first_frame = 1;
        if (!args->resume.empty()) {
            const sim::Journal journal = sim::read_journal(args->resume, header);
            sim::resume(method, journal);
            if (!journal.strokes.empty()) first_frame = journal.strokes.back().frame + 1;
            log::info("resumed {}: {} stroke(s), {} cut(s), going on from frame {} (t = {:g} s)", args->resume, journal.strokes.size(),
                      method.cut_count(), first_frame, (first_frame - 1) * dt);
        }
        // Device runs (and resumed ones) keep a journal beside their output, a line per stroke.
        std::unique_ptr<sim::JournalWriter> journal;
        if (device || !args->resume.empty()) {
            journal = std::make_unique<sim::JournalWriter>(sim::journal_path(out), header, method, first_frame - 1, (first_frame - 1) * dt);
            log::info("journal: {} (each stroke synced to disk as it ends)", journal->path().string());
        }
        sim::StrokeEnds stroke_ends;
        StagingDir staging(out); // a run that fails leaves nothing behind
        const std::filesystem::path& dir = staging.path();
        log::info("{}: {}, {} frames of {} s ({}; {})", args->scene, method.description(), frames, dt,
                  scene.solver.mode == io::SolverMode::static_equilibrium ? "quasi-static" : "implicit Euler", method.linear_solver());

        sim::RunRecord record(args->scene, method, dt);
        if (opened.choice) record.document()["level_choice"] = level_choice_json(*opened.choice);
        if (!args->resume.empty())
            record.document()["resumed_from"] = {{"journal", args->resume}, {"frame", first_frame - 1}, {"cuts", method.cut_count()}};
        std::vector<sim::ForceSample> tool_forces; // without a device: the first placed tool's, per frame
        sim::FrameLoop loop(scene, method, tools, device.get());
        loop.go_on_from(first_frame - 1);
        // A device run keeps the budget as it goes: a level coarser while frames miss it, and back.
        if (device && opened.choice)
            if (auto governor = sim::level_governor(scene, *opened.choice, method.coarsest_level())) {
                log::info("levels {} to {}: the run moves coarser when its frames miss {:g} ms for a second, and back when there is room{}",
                          governor->settings().finest, governor->settings().coarsest, governor->settings().budget_ms,
                          device->replaying() ? " (a replay follows the recording's levels)" : "");
                loop.govern_levels(std::move(*governor));
            }
        const int vtu_every = scene.output.vtu_every_n_frames;
        std::vector<std::pair<double, std::string>> vtu_frames;
        const auto write_fem_mesh = [&](int f, double t) {
            char name[32];
            std::snprintf(name, sizeof name, "mesh_%05d.vtu", f);
            io::write_vtu(*method.fem_mesh(), dir / name);
            vtu_frames.emplace_back(t, name);
        };
        if (vtu_every > 0 && first_frame == 1) write_fem_mesh(0, 0.0);
        Progress progress("simulating", static_cast<std::uint64_t>(frames));
        // A live run's frames keep to wall time: a frame that ends early waits; a late one does not
        // (the haptic loop goes on at 1 kHz meanwhile, on the snapshot it has).
        const auto wall_start = std::chrono::steady_clock::now();
        int late_frames = 0;
        for (int f = first_frame; f <= frames; ++f) {
            if (device && device->live()) {
                const auto due = wall_start + std::chrono::duration_cast<std::chrono::steady_clock::duration>(
                                                  std::chrono::duration<double>((f - first_frame) * dt));
                if (std::chrono::steady_clock::now() > due + std::chrono::duration<double>(dt)) ++late_frames;
                std::this_thread::sleep_until(due);
            }
            const sim::FrameStats frame = loop.next();
            record.add(frame, method);
            if (journal && frame.level_change) // a journal holds one level's motion: a new one, with the cuts so far
                journal = std::make_unique<sim::JournalWriter>(sim::journal_path(out), sim::journal_header(args->scene, method), method,
                                                               frame.frame, frame.t_s);
            if (journal && stroke_ends.after_frame(frame)) journal->end_stroke(method, frame.frame, frame.t_s);
            if (!device)
                for (const sim::ToolFrame& t : frame.tools.tools)
                    if (t.placed) {
                        tool_forces.push_back({frame.t_s, t.position_mm, t.force_n});
                        break;
                    }
            if (pictures && f % args->render_every == 0) pictures->write(dir / sim::frame_file_name(f, "png"), method, tools, scene);
            if (f % scene.output.mesh_every_n_frames == 0) write_surface(dir / sim::frame_file_name(f, "obj"), method);
            if (vtu_every > 0 && f % vtu_every == 0) write_fem_mesh(f, frame.t_s);
            progress.update(static_cast<std::uint64_t>(f));
        }
        progress.finish();
        if (device) device->finish(method);
        const double wall_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - wall_start).count();
        const double simulated_s = (frames - first_frame + 1) * dt;
        if (late_frames > (frames - first_frame + 1) / 20) // a few late frames are not worth a word
            log::warn("the simulation ran slower than real time: {:.2f} s simulated in {:.2f} s ({} of {} frames started more than a "
                      "frame late; a coarser level, or \"levels\": \"auto\" with a budget, keeps up)",
                      simulated_s, wall_s, late_frames, frames - first_frame + 1);
        if (journal) journal->end_stroke(method, loop.frames(), loop.frames() * dt); // the stroke under way at the end
        record.finish(method);
        for (const auto& [tool, touched] : record.tools_given_no_patch())
            log::warn("tool \"{}\": \"haptic_subdivision\" asked for a contact patch, but none was built in the {} frame(s) it touched: the "
                      "method measured no give at its contact (only the branched grid measures it, and not where the elements touched hold "
                      "rigid material), or the contact was wider than a patch holds (docs/haptics.md)",
                      tool, touched);
        write_surface(dir / "final.obj", method);
        {
            const surface::SurfaceMesh m = method.surface_mesh();
            const auto color_of = [&](std::int32_t label) {
                const auto own = scene.object.label_colors.find(label);
                return own != scene.object.label_colors.end() ? own->second : label_color(label);
            };
            const auto name_of = [&](std::int32_t label) {
                const auto own = scene.object.label_names.find(label);
                return own != scene.object.label_names.end() ? own->second : "label " + std::to_string(label);
            };
            io::write_glb(dir / "final.glb", m.positions, m.triangles, m.labels, color_of, name_of);
        }
        if (!vtu_frames.empty()) io::write_pvd(vtu_frames, dir / "mesh.pvd");
        if (!scene.output.volumes.empty()) {
            const grid::LabelGrid voxels = method.rest_voxels();
            for (const std::string& format : scene.output.volumes) {
                const std::filesystem::path file = dir / ("final." + format);
                if (format == "vdb")
                    voxels.save(file);
                else
                    io::write_label_map(voxels, file);
            }
        }
        if (pictures) pictures->write(dir / "final.png", method, tools, scene);
        if (device) {
            // forces.csv for the first device, as ever; forces_2.csv ... for the others.
            nlohmann::json devices = nlohmann::json::array();
            for (std::size_t i = 0; i < device->device_count(); ++i) {
                const std::string name = i == 0 ? "forces" : "forces_" + std::to_string(i + 1);
                sim::write_forces(dir, device->forces(i), "force on the device, " + scene.tools[device->tool(i)].name, name);
                devices.push_back({{"device", device->device_name(i)},
                                   {"tool", scene.tools[device->tool(i)].name},
                                   {"forces", name + ".csv"},
                                   {"faults", device->faults(i)}});
            }
            record.document()["devices"] = std::move(devices);
            if (device->live()) {
                record.document()["haptic_loop"] = device->loop_figures();
                record.document()["haptic_loop"]["late_frames"] = late_frames;
                record.document()["haptic_loop"]["real_time_factor"] = simulated_s / std::max(wall_s, 1e-9);
            }
            if (!args->record.empty()) haptics::write_recording(args->record, device->recording());
        } else if (!tool_forces.empty()) {
            sim::write_forces(dir, tool_forces, "contact force on the tool");
        }
        write_atomically(dir / "stats.json", [&](const std::filesystem::path& tmp) { std::ofstream(tmp) << record.document().dump(1) << '\n'; });
        staging.commit();
        log::info("wrote {}: stats.json, final.obj, final.glb and {} frame meshes; mean step {:.2f} ms, max displacement {:.3f} mm", out.string(),
                  frames / scene.output.mesh_every_n_frames - (first_frame - 1) / scene.output.mesh_every_n_frames,
                  record.total_step_ms() / std::max(frames - first_frame + 1, 1),
                  record.last_step().max_displacement_mm);
    });
}

} // namespace vox::app
