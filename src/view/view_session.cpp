#include "view/view_session.hpp"

#include "core/error.hpp"
#include "core/log.hpp"
#include "haptics/coupled_tool.hpp"
#include "haptics/force_devices.hpp"
#include "haptics/haptic_loop.hpp"
#include "haptics/hid_devices.hpp"
#include "haptics/paced_device.hpp"
#include "haptics/pointer_device.hpp"
#include "haptics/spacemouse_device.hpp"
#include "io/scene.hpp"
#include "io/scene_object.hpp"
#include "io/tool_script.hpp"
#include "sim/dbg_method.hpp"
#include "sim/device_run.hpp"
#include "sim/isxfem_method.hpp"
#include "sim/journal.hpp"
#include "sim/method_factory.hpp"
#include "view/scene_pictures.hpp"
#include "view/view_channels.hpp"
#include "view/view_simulation.hpp"
#include "view/view_window.hpp"

#include <tbb/global_control.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <filesystem>
#include <map>
#include <optional>
#include <thread>

namespace vox::view {
namespace {

/// The tool each device drives (ViewOptions::devices, ::tools); InputError naming the option.
std::vector<std::size_t> driven_tools(const io::Scene& scene, const ViewOptions& options)
{
    const std::size_t devices = options.devices.size();
    if (devices == 0) throw InputError("--device: give at least one");
    if (devices > 1 ? options.tools.size() != devices : options.tools.size() > 1)
        throw InputError("--tool: give one per --device, in the same order (" + std::to_string(devices) + " device(s), " +
                         std::to_string(options.tools.size()) + " tool(s))");
    if (std::count(options.devices.begin(), options.devices.end(), "mouse") > 1) throw InputError("--device: the mouse can drive one tool only");
    std::vector<std::size_t> driven;
    for (std::size_t d = 0; d < devices; ++d) driven.push_back(sim::tool_named(scene, options.tools.empty() ? std::string() : options.tools[d]));
    sim::check_device_tools(scene, driven);
    return driven;
}

} // namespace

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
    const std::vector<std::size_t> driven = driven_tools(scene, options); // before the object is loaded
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

    // Where each device's tool starts: where the scene's script puts it, else above the object
    // (several devices side by side).
    render::DrawMesh first = surface_picture(*method, 0);
    Eigen::AlignedBox3d bounds;
    bounds.setEmpty();
    for (const std::uint32_t i : first.indices) bounds.extend(first.positions[i].cast<double>());
    const double radius = 0.5 * bounds.diagonal().norm();
    // TAB moves a lone device to the next tool (not a script: it follows one tool's entries).
    const bool single = driven.size() == 1 && options.devices.front() != "script";
    std::vector<io::ToolPose> starts;
    for (std::size_t d = 0; d < driven.size(); ++d) {
        io::ToolPose pose = io::tool_pose(loaded, driven[d], 0.0);
        if (!pose.placed)
            pose.position_mm = bounds.center() + (radius + 10.0) * spec.up + (static_cast<double>(d) * 0.5 * radius) * spec.up.unitOrthogonal();
        starts.push_back(pose);
    }
    constexpr std::size_t snapshot_capacity = 50000;
    ViewChannels channels(snapshot_capacity, driven.size());
    // The devices. The mouse is one pointer: it drives at most one tool (else it only moves the camera).
    const auto mouse_hand = std::find(options.devices.begin(), options.devices.end(), "mouse") - options.devices.begin();
    const io::ToolPose& pointed = starts[static_cast<std::size_t>(mouse_hand) < starts.size() ? static_cast<std::size_t>(mouse_hand) : 0];
    haptics::PointerDevice pointer(pointed.position_mm, pointed.orientation);
    std::vector<std::unique_ptr<haptics::Device>> owned; // controllers and scripts
    std::vector<haptics::Device*> devices;
    std::vector<haptics::HidDevice> controllers; // 6-DoF controllers that can be opened, taken in turn
    if (std::any_of(options.devices.begin(), options.devices.end(), [](const std::string& d) { return d == "auto" || d == "hid"; })) {
        try {
            for (const haptics::HidDevice& d : haptics::enumerate_hid_devices())
                if (d.six_dof && d.openable) controllers.push_back(d);
        } catch (const InputError& e) {
            if (std::find(options.devices.begin(), options.devices.end(), "hid") != options.devices.end()) throw;
            log::info("no HID devices ({}); the mouse drives the tool", e.what());
        }
    }
    bool mouse_taken = false;
    std::map<std::string, int> taken; // force-feedback devices opened, per backend
    for (std::size_t d = 0; d < driven.size(); ++d) {
        const std::string& kind = options.devices[d];
        const io::ToolPose& at = starts[d];
        if (kind == "script") {
            owned.push_back(std::make_unique<haptics::PacedDevice>(sim::script_key_frames(loaded, driven[d]), channels.simulation_t_s, scene.solver.dt_s));
        } else if (kind == "hid" || (kind == "auto" && !controllers.empty())) {
            if (controllers.empty())
                throw InputError("--device hid: no " + std::string(d ? "further " : "") + "6-DoF controller can be opened. " +
                                 (d ? haptics::udev_rule_advice() : haptics::explain_no_hid_devices()));
            const haptics::HidDevice c = controllers.front();
            controllers.erase(controllers.begin());
            owned.push_back(std::make_unique<haptics::SpaceMouseDevice>(c.path, c.product, at.position_mm, at.orientation));
        } else if (haptics::is_force_device(kind)) {
            // An absolute device: its frame placed in the scene (the tool's "device_frame", else
            // its origin where the tool starts), its first button a clutch.
            owned.push_back(haptics::open_force_device(kind, taken[kind]++, sim::device_frame(scene.tools[driven[d]], at.position_mm)));
        } else { // the mouse
            if (mouse_taken) throw InputError("--device: the mouse can drive one tool only (device " + std::to_string(d + 1) + ")");
            mouse_taken = true;
            devices.push_back(&pointer);
            continue;
        }
        devices.push_back(owned.back().get());
    }
    for (std::size_t d = 0; d < driven.size(); ++d)
        log::info("tool \"{}\" is driven by: {}", scene.tools[driven[d]].name, devices[d]->name());

    // The haptic side: one coupled tool per scene tool (one device: the active one's is used), one
    // loop serving every device, each with its own coupling and safety stage.
    std::vector<std::unique_ptr<haptics::CoupledTool>> coupled;
    for (std::size_t k = 0; k < scene.tools.size(); ++k) {
        haptics::CouplingSettings coupling = sim::device_coupling(scene.tools[k], {});
        for (std::size_t d = 0; d < driven.size(); ++d) // a device's own limits where it declares them
            if (driven[d] == k) coupling = sim::device_coupling(scene.tools[k], devices[d]->limits());
        coupled.push_back(std::make_unique<haptics::CoupledTool>(
            tools.shape(k), contact::ContactParameters{scene.tools[k].push_margin_mm, scene.tools[k].contact_stiffness_n_per_mm}, coupling,
            snapshot_capacity));
    }
    ViewRequests& requests = channels.requests;
    const auto t0 = std::chrono::steady_clock::now();
    auto now_s = [t0] { return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count(); };
    // The scene tool device d drives now (one device: the active one).
    auto tool_of = [&](std::size_t d) { return single ? requests.active.load(std::memory_order_relaxed) : static_cast<int>(driven[d]); };
    std::vector<haptics::HapticChannel> served;
    for (std::size_t d = 0; d < driven.size(); ++d) {
        const haptics::SafetySettings safety = haptics::safety_for(devices[d]->limits());
        const bool mouse = devices[d] == &pointer;
        served.push_back({devices[d],
                          [&, d, mouse](const haptics::DeviceState& s, double& age) -> Eigen::Vector3d {
                              HandChannel& hand = channels.hand(d);
                              // The snapshot the last tick's prepare took, the contact measured on it
                              // (a newer one is taken after this tick's force is sent).
                              const contact::SurfacePoints& surface = hand.snapshots.read_slot();
                              age = now_s() - surface.t_s;
                              const int k = tool_of(d);
                              haptics::CoupledTool& tool = *coupled[static_cast<std::size_t>(k)];
                              tool.set_passing(hand.passing.load(std::memory_order_relaxed));
                              const Eigen::Vector3d f = tool.update(s, surface, 1e-3);
                              hand.proxies.write_slot() = {k, tool.handed_pose(), mouse ? pointer.target() : s.position_mm,
                                                           tool.coupling_stiffness_n_per_mm(), s.buttons};
                              hand.proxies.publish();
                              if (d == 0) requests.ticks.fetch_add(1, std::memory_order_relaxed);
                              return f;
                          },
                          safety,
                          [&, d](const haptics::DeviceState& s) {
                              coupled[static_cast<std::size_t>(tool_of(d))]->prepare(s, channels.hand(d).snapshots.latest(), 1e-3);
                          }});
    }
    haptics::HapticLoop loop(std::move(served));

    log::info("viewer: {} ({}), tools: {}; press H for the keys", scene_path, method->description(), scene.tools.size());
    ViewSimulationOptions sim_options;
    sim_options.grid_levels = grid_levels;
    sim_options.smooth = options.smooth;
    sim_options.out_dir = options.out_dir;
    sim_options.hands.clear();
    for (std::size_t d = 0; d < driven.size(); ++d)
        sim_options.hands.push_back({driven[d], starts[d].position_mm, options.devices[d], devices[d], haptics::is_force_device(options.devices[d])});
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
    window.now_s = now_s;
    run_window(window, channels, pointer, [&loop] { loop.start(); });
    requests.stop = true;
    if (simulation_thread.joinable()) simulation_thread.join(); // before reading what it left
    loop.stop();
    if (!failure.empty()) throw InputError(scene_path + ": the simulation stopped: " + failure);
    for (std::size_t d = 0; d < driven.size(); ++d) { // where each device left its tool
        const auto k = static_cast<std::size_t>(tool_of(d));
        const Eigen::Vector3d at = coupled[k]->proxy().position;
        log::info("tool \"{}\" ({}) ended at ({:.2f}, {:.2f}, {:.2f}) mm", scene.tools[k].name, options.devices[d], at.x(), at.y(), at.z());
    }
}

} // namespace vox::view
