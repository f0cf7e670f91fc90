#include "view/view_session.hpp"

#include "core/error.hpp"
#include "core/log.hpp"
#include "haptics/coupled_tool.hpp"
#include "haptics/haptic_loop.hpp"
#include "haptics/hid_devices.hpp"
#include "haptics/pointer_device.hpp"
#include "haptics/spacemouse_device.hpp"
#include "io/scene.hpp"
#include "io/scene_object.hpp"
#include "io/tool_script.hpp"
#include "sim/dbg_method.hpp"
#include "sim/isxfem_method.hpp"
#include "sim/journal.hpp"
#include "sim/method_factory.hpp"
#include "view/scene_pictures.hpp"
#include "view/view_channels.hpp"
#include "view/view_simulation.hpp"
#include "view/view_window.hpp"

#include <tbb/global_control.h>

#include <atomic>
#include <chrono>
#include <filesystem>
#include <optional>
#include <thread>

namespace vox::view {

void run_view(const std::string& scene_path, const ViewOptions& options)
{
    const io::Scene loaded = io::load_scene(scene_path);
    if (!options.resume.empty() && !std::filesystem::is_regular_file(options.resume)) // before the object is loaded
        throw file_error(options.resume, "no such file (--resume takes a session journal)");
    if (loaded.tools.empty()) throw loaded.error("tools", "the viewer needs at least one tool to sculpt with");
    // Not silently the other method: a researcher comparing the two must see the one asked for.
    // The user moves the tools: the script does not.
    io::Scene scene = loaded;
    scene.script.clear();
    if (!options.solver.empty()) io::use_method(scene, io::solver_type_named(options.solver));
    render::CameraSpec spec = render::parse_camera(options.camera);
    spec.up = scene_up(scene);
    spec.orthographic = false; // the viewer orbits in perspective
    const auto labels = std::make_shared<const grid::LabelGrid>(io::load_scene_object(scene));
    const int level = std::max(scene.object.levels, 1);
    // The branched grid has two levels above the scene's, for the coarser-level key.
    int grid_levels = std::min(6, level + std::max(2, scene.solver.type == io::SolverType::shape_matching ? scene.solver.sm_cluster_levels : 0));
    std::unique_ptr<sim::Method> method;
    std::optional<sim::LevelGovernor> governor;
    if (scene.solver.type == io::SolverType::isxfem) {
        method = std::make_unique<sim::IsxfemMethod>(scene, labels, level);
    } else if (scene.object.auto_levels) {
        // The level chosen as `run` chooses it, on the frames the scene's script makes (the
        // viewer's tools follow the user, but the script says where the work will be).
        io::Scene scripted = loaded;
        if (!options.solver.empty()) io::use_method(scripted, scene.solver.type);
        sim::OpenedMethod opened = sim::open_method(scripted, labels);
        method = std::move(opened.method);
        grid_levels = method->coarsest_level();
        if (opened.choice) governor = sim::level_governor(scene, *opened.choice, grid_levels);
    } else {
        method = std::make_unique<sim::DbgMethod>(scene, labels, level, grid_levels);
    }
    sim::ToolPolicy tools(scene);

    // The session journal (docs/journal.md): OUT/SCENE.journal. With --resume, the object starts as
    // that journal's last stroke left it; otherwise the last session's journal of this scene is
    // offered (J) until the first cut.
    const std::filesystem::path session_journal =
        std::filesystem::path(options.out_dir) / (std::filesystem::path(scene_path).stem().string() + ".journal");
    sim::JournalHeader header = sim::journal_header(scene_path, *method);
    header.any_level = scene.object.auto_levels; // the session may have moved between levels
    std::optional<sim::Journal> offered;
    if (!options.resume.empty()) {
        const sim::Journal journal = sim::read_journal(options.resume, header);
        sim::resume(*method, journal);
        log::info("resumed {}: {} stroke(s), {} cut(s)", options.resume, journal.strokes.size(), method->cut_count());
    } else if (std::filesystem::exists(session_journal)) {
        try {
            sim::Journal earlier = sim::read_journal(session_journal, header);
            if (!earlier.cuts().empty()) {
                log::info("{}: an earlier session left {} stroke(s): press J in the window to resume them", session_journal.string(),
                          earlier.strokes.size());
                offered = std::move(earlier);
            }
        } catch (const InputError& e) {
            log::info("an earlier journal is not offered: {}", e.what());
        }
    }

    // Where the first tool starts: where the scene's script puts it, else above the object.
    render::DrawMesh first = surface_picture(*method, 0);
    Eigen::AlignedBox3d bounds;
    bounds.setEmpty();
    for (const std::uint32_t i : first.indices) bounds.extend(first.positions[i].cast<double>());
    const double radius = 0.5 * bounds.diagonal().norm();
    const io::ToolPose scripted = io::tool_pose(loaded, 0, 0.0);
    const Eigen::Vector3d start = scripted.placed ? scripted.position_mm : Eigen::Vector3d(bounds.center() + (radius + 10.0) * spec.up);
    const Eigen::Quaterniond start_orientation = scripted.placed ? scripted.orientation : Eigen::Quaterniond::Identity();
    haptics::PointerDevice pointer(start, start_orientation);
    // The device: a 6-DoF controller when there is one (the mouse then only moves the camera),
    // else the mouse as a pointer.
    std::unique_ptr<haptics::SpaceMouseDevice> controller;
    if (options.device != "mouse") {
        std::vector<haptics::HidDevice> found;
        try {
            found = haptics::enumerate_hid_devices();
        } catch (const InputError& e) {
            if (options.device == "hid") throw;
            log::info("no HID devices ({}); the mouse drives the tool", e.what());
        }
        for (const haptics::HidDevice& d : found)
            if (d.six_dof && d.openable) {
                controller = std::make_unique<haptics::SpaceMouseDevice>(d.path, d.product, start, start_orientation);
                break;
            }
        if (!controller && options.device == "hid")
            throw InputError("--device hid: no 6-DoF controller can be opened. " +
                             (found.empty() ? haptics::explain_no_hid_devices() : haptics::udev_rule_advice()));
    }
    haptics::Device& device = controller ? static_cast<haptics::Device&>(*controller) : static_cast<haptics::Device&>(pointer);
    log::info("the tool is driven by: {}", device.name());

    // The haptic side: one coupled tool per scene tool, the active one used.
    constexpr std::size_t snapshot_capacity = 50000;
    std::vector<std::unique_ptr<haptics::CoupledTool>> coupled;
    for (std::size_t k = 0; k < scene.tools.size(); ++k)
        coupled.push_back(std::make_unique<haptics::CoupledTool>(
            tools.shape(k), contact::ContactParameters{scene.tools[k].push_margin_mm, scene.tools[k].contact_stiffness_n_per_mm},
            haptics::CouplingSettings{}, snapshot_capacity));
    ViewChannels channels(snapshot_capacity);
    ViewRequests& requests = channels.requests;
    const auto t0 = std::chrono::steady_clock::now();
    auto now_s = [t0] { return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count(); };
    haptics::HapticLoop loop(
        device,
        [&](const haptics::DeviceState& s, double& age) -> Eigen::Vector3d {
            const contact::SurfacePoints& surface = channels.snapshots.latest();
            age = now_s() - surface.t_s;
            const int k = requests.active.load(std::memory_order_relaxed);
            const Eigen::Vector3d f = coupled[static_cast<std::size_t>(k)]->update(s, surface, 1e-3);
            channels.proxies.write_slot() = {k, coupled[static_cast<std::size_t>(k)]->proxy(), controller ? s.position_mm : pointer.target()};
            channels.proxies.publish();
            requests.ticks.fetch_add(1, std::memory_order_relaxed);
            return f;
        },
        haptics::SafetySettings{});

    log::info("viewer: {} ({}), tools: {}; press H for the keys", scene_path, method->description(), scene.tools.size());
    ViewSimulationOptions sim_options;
    sim_options.grid_levels = grid_levels;
    sim_options.smooth = options.smooth;
    sim_options.out_dir = options.out_dir;
    sim_options.start_mm = start;
    sim_options.scene_file = scene_path;
    sim_options.journal = session_journal;
    sim_options.offered = std::move(offered);
    sim_options.governor = std::move(governor);
    ViewSimulation simulation(scene, std::move(method), tools, channels, sim_options);
    // The simulation thread: from here on the only one to touch the method, the tools and the
    // scene's tool settings.
    std::string failure;
    std::thread simulation_thread([&] {
        try {
            const tbb::global_control one_thread(tbb::global_control::max_allowed_parallelism, 1); // the other core is the loop's
            simulation.run(now_s);
        } catch (const std::exception& e) {
            failure = e.what();
            requests.stop = true;
        }
    });
    struct Joiner { // stop the threads however this function ends
        std::atomic<bool>& stop;
        std::thread& thread;
        haptics::HapticLoop& loop;
        ~Joiner()
        {
            stop = true;
            if (thread.joinable()) thread.join();
            loop.stop();
        }
    } joiner{requests.stop, simulation_thread, loop};

    // The window, on this thread.
    WindowSetup window;
    window.title = scene_path;
    window.options = options;
    window.camera = spec;
    window.first = first;
    window.centre = bounds.center();
    window.radius = radius;
    window.tool_count = scene.tools.size();
    window.level = level;
    window.now_s = now_s;
    run_window(window, channels, pointer, [&loop] { loop.start(); });
    requests.stop = true;
    if (simulation_thread.joinable()) simulation_thread.join(); // before reading what it left
    loop.stop();
    if (!failure.empty()) throw InputError(scene_path + ": the simulation stopped: " + failure);
}

} // namespace vox::view
