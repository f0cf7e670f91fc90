#include "view/view_session.hpp"

#include "view/scene_pictures.hpp"
#include "sim/dbg_method.hpp"
#include "sim/frame_loop.hpp"
#include "sim/isxfem_method.hpp"
#include "sim/undo_history.hpp"
#include "core/error.hpp"
#include "core/log.hpp"
#include "haptics/coupled_tool.hpp"
#include "haptics/haptic_loop.hpp"
#include "haptics/hid_devices.hpp"
#include "haptics/pointer_device.hpp"
#include "haptics/spacemouse_device.hpp"
#include "io/mesh_writer.hpp"
#include "io/scene.hpp"
#include "io/scene_object.hpp"
#include "io/tool_script.hpp"
#include "render/display_lod.hpp"
#include "render/renderer.hpp"
#include "render/text_overlay.hpp"
#include "render/window.hpp"

#include <GLFW/glfw3.h>
#include <tbb/global_control.h>

#include <atomic>
#include <chrono>
#include <cmath>
#include <thread>

namespace vox::view {
namespace {

using clock_type = std::chrono::steady_clock;

/// What the simulation thread shows the window.
struct RenderState {
    std::vector<render::DrawMesh> meshes; ///< the surface first, then the tools (and the cage)
    double t_s = 0.0;
    std::size_t elements = 0;
    int level = 0;
    std::string tool;                     ///< the active tool and what it does
    int smooth = 0;                       ///< display smoothing the window is to give the surface
};

/// The tool the haptic thread moved, where, and where the device is heading (the surface
/// snapshot must reach that far).
struct ProxyPose {
    int tool = 0;
    contact::PlacedShape pose;
    Eigen::Vector3d heading = Eigen::Vector3d::Zero();
};

/// An orbiting camera: yaw and pitch about `up` around a target, at a distance.
struct Orbit {
    render::CameraSpec spec;
    Eigen::Vector3d target = Eigen::Vector3d::Zero();
    double distance = 100.0, radius = 50.0;
    [[nodiscard]] render::Camera camera() const
    {
        render::Camera c;
        c.up = spec.up;
        c.target = target;
        c.eye = target + distance * render::view_direction(spec);
        c.near_mm = std::max(1e-3 * distance, distance - 3.0 * radius);
        c.far_mm = distance + 3.0 * radius;
        return c;
    }
};

const char* const key_map = "mouse left: move the tool (a stroke)   wheel: nearer / farther\n"
                            "mouse right: orbit   middle: pan   shift + wheel: zoom\n"
                            "R: reset the view   TAB: next tool   1 push  2 cut  3 wet\n"
                            "M: cut mode (remove / separate)   U: undo the last stroke\n"
                            "SPACE: pause / run   N: one step while paused\n"
                            "+ / -: coarser / finer level (deformation restarts)\n"
                            "C: element cage   V: the fine voxels   L: level of detail\n"
                            "S: save (.obj, .vdb)   P: screenshot   H, ?: help   Q, ESC: quit";

} // namespace

void run_view(const std::string& scene_path, const ViewOptions& options)
{
    const io::Scene loaded = io::load_scene(scene_path);
    if (loaded.tools.empty()) throw loaded.error("tools", "the viewer needs at least one tool to sculpt with");
    // Not silently the other method: a researcher comparing the two must see the one asked for.
    // The user moves the tools: the script does not.
    io::Scene scene = loaded;
    scene.script.clear();
    if (!options.solver.empty()) io::use_method(scene, options.solver == "isxfem" ? io::SolverType::isxfem : io::SolverType::dbg);
    render::CameraSpec spec = render::parse_camera(options.camera);
    spec.up = scene_up(scene);
    spec.orthographic = false; // the viewer orbits in perspective
    const auto labels = std::make_shared<const grid::LabelGrid>(io::load_scene_object(scene));
    const int level = std::max(scene.object.levels, 1);
    // The branched grid has two levels above the scene's, for the coarser-level key.
    const int grid_levels = std::min(6, level + 2);
    std::unique_ptr<sim::Method> method;
    if (scene.solver.type == io::SolverType::isxfem) method = std::make_unique<sim::IsxfemMethod>(scene, labels, level);
    else method = std::make_unique<sim::DbgMethod>(scene, labels, level, grid_levels);
    sim::ToolPolicy tools(scene);
    sim::FrameLoop sim_loop(scene, *method, tools);

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
    haptics::TripleBuffer<contact::SurfacePoints> snapshots{contact::SurfacePoints(snapshot_capacity)};
    haptics::TripleBuffer<ProxyPose> proxies;
    haptics::TripleBuffer<RenderState> pictures;
    std::atomic<int> active{0};
    std::atomic<bool> stop{false}, paused{false}, step_once{false}, show_cage{false}, show_voxels{false}, save_object{false}, picture_taken{true};
    std::atomic<bool> stroke_started{false}, undo{false}, toggle_cut_mode{false};
    std::atomic<int> level_change{0}, set_action{-1}; // requests from the window to the simulation thread
    std::atomic<std::uint64_t> ticks{0}, frames{0};
    const auto t0 = clock_type::now();
    auto now_s = [&t0] { return std::chrono::duration<double>(clock_type::now() - t0).count(); };

    haptics::HapticLoop loop(
        device,
        [&](const haptics::DeviceState& s, double& age) -> Eigen::Vector3d {
            const contact::SurfacePoints& surface = snapshots.latest();
            age = now_s() - surface.t_s;
            const int k = active.load(std::memory_order_relaxed);
            const Eigen::Vector3d f = coupled[static_cast<std::size_t>(k)]->update(s, surface, 1e-3);
            proxies.write_slot() = {k, coupled[static_cast<std::size_t>(k)]->proxy(), controller ? s.position_mm : pointer.target()};
            proxies.publish();
            ticks.fetch_add(1, std::memory_order_relaxed);
            return f;
        },
        haptics::SafetySettings{});

    log::info("viewer: {} ({}), tools: {}; press H for the keys", scene_path, method->description(), scene.tools.size());
    // The simulation thread (from here on the only one to touch the grid, the simulation, the
    // tools' session and the scene's tool settings).
    std::string failure;
    std::thread simulation([&] {
        try {
            const tbb::global_control one_thread(tbb::global_control::max_allowed_parallelism, 1); // the other core is the loop's
            const double dt = scene.solver.dt_s;
            int driven = -1, simulated = level;
            contact::PlacedShape pose{&tools.shape(0), start, Eigen::Quaterniond::Identity()};
            Eigen::Vector3d heading = start;
            sim::UndoHistory history; // the state before each stroke
            // The device lets go of its tool: after the object changed under it.
            auto let_go = [&] {
                tools.reset();
                if (driven >= 0) tools.release(static_cast<std::size_t>(driven));
                driven = -1;
            };
            std::uint64_t frame = 0;
            auto next = clock_type::now();
            while (!stop.load()) {
                // Requests from the window.
                if (const int d = level_change.exchange(0); d != 0) {
                    const int at = std::clamp(simulated + d, 1, grid_levels);
                    if (at != simulated) {
                        method = method->at_level(at);
                        sim_loop.set_method(*method);
                        let_go();
                        simulated = at;
                        history.clear(); // the deformation restarts from rest at the new level
                        log::info("level {}: {} elements ({}the deformation from rest)", at, method->element_count(),
                                  method->name() == std::string("dbg") ? "the cuts kept, " : "uncut: Is-XFEM cannot carry cuts across levels yet; ");
                    }
                }
                if (undo.exchange(false)) {
                    if (history.undo(*method)) {
                        let_go();
                        log::info("undo: back to before the last stroke");
                    } else {
                        log::info("{}", method->checkpoint() ? "undo: nothing to undo" : "undo: not available with this method yet (docs/viewer.md)");
                    }
                }
                if (const int a = set_action.exchange(-1); a >= 0) {
                    io::ToolSpec& t = scene.tools[static_cast<std::size_t>(active.load())];
                    t.action = a == 0 ? io::ToolAction::push : a == 1 ? io::ToolAction::cut : io::ToolAction::wet;
                }
                if (toggle_cut_mode.exchange(false)) {
                    io::ToolSpec& t = scene.tools[static_cast<std::size_t>(active.load())];
                    if (scene.solver.type == io::SolverType::isxfem) log::info("Is-XFEM cuts by separating only (it cannot remove material)");
                    else t.cut_mode = t.cut_mode == io::CutMode::remove ? io::CutMode::separate : io::CutMode::remove;
                }
                if (paused.load() && !step_once.exchange(false)) {
                    std::this_thread::sleep_for(std::chrono::milliseconds(5));
                    next = clock_type::now();
                    continue;
                }
                if (proxies.update()) {
                    const ProxyPose& p = proxies.read_slot();
                    if (p.tool != driven && driven >= 0) tools.release(static_cast<std::size_t>(driven));
                    driven = p.tool;
                    pose = p.pose;
                    heading = p.heading;
                }
                // A stroke's checkpoint before any of its cuts: the window flags the stroke before it
                // moves the pointer, so a pose read above that belongs to the stroke sees the flag.
                if (stroke_started.exchange(false)) history.before_stroke(*method);
                if (driven >= 0) tools.drive(static_cast<std::size_t>(driven), pose.position, pose.orientation);
                try {
                    sim_loop.next();
                } catch (const InputError& e) { // a step that cannot be trusted: said, and the session paused to keep it
                    log::warn("{}; paused (SPACE runs on, U undoes the last stroke)", e.what());
                    paused = true;
                }
                contact::SurfacePoints& out = snapshots.write_slot();
                const io::ToolSpec& held = scene.tools[static_cast<std::size_t>(std::max(driven, 0))];
                Eigen::AlignedBox3d near = pose.world_bounds(held.push_margin_mm + 5.0);
                near.extend(contact::PlacedShape{pose.shape, heading, pose.orientation}.world_bounds(held.push_margin_mm + 5.0));
                method->sample_surface(near, held, out);
                out.t_s = now_s();
                snapshots.publish();
                if (save_object.exchange(false)) try {
                    const std::filesystem::path dir(options.out_dir);
                    const surface::SurfaceMesh m = method->surface_mesh();
                    for (const char* name : {"view_surface.obj", "view_surface.ply", "view_surface.stl"})
                        io::write_mesh((dir / name).string(), m.positions, m.triangles, m.labels);
                    log::info("saved the deformed surface to {}.obj, .ply and .stl ({} triangles)", (dir / "view_surface").string(), m.triangles.size());
                    if (const auto* dbg = dynamic_cast<const sim::DbgMethod*>(method.get())) { // the voxels left, as the branched grid has them
                        const grid::FineVoxels& voxels = dbg->grid().voxels();
                        grid::LabelGrid kept(voxels.index_to_world());
                        for (std::uint32_t v = 0; v < voxels.slots(); ++v)
                            if (voxels.alive(v)) kept.set(voxels.coord(v), voxels.label(v));
                        kept.save(dir / "view_object.vdb");
                        log::info("saved the object's {} voxels to {}", voxels.alive_count(), (dir / "view_object.vdb").string());
                    }
                } catch (const std::exception& e) {
                    log::warn("not saved: {}", e.what()); // the session goes on
                }
                if (picture_taken.exchange(false)) { // the window has the last one: make the next
                    RenderState& r = pictures.write_slot();
                    r.meshes.clear();
                    const auto* dbg = dynamic_cast<const sim::DbgMethod*>(method.get()); // voxels and cages are the branched grid's
                    if (show_voxels.load() && dbg) {
                        r.meshes.push_back(voxel_boxes(dbg->simulation()));
                        r.smooth = 0;
                    } else {
                        r.meshes.push_back(surface_picture(*method, 0)); // smoothed by the window's thread
                        r.smooth = options.smooth;
                    }
                    for (std::size_t k = 0; k < scene.tools.size(); ++k) add_tool_drawings(tools.placed(k), scene.tools[k].push_margin_mm, r.meshes);
                    if (show_cage.load() && dbg) r.meshes.push_back(element_cage(dbg->simulation()));
                    r.t_s = static_cast<double>(frame + 1) * dt;
                    r.elements = method->element_count();
                    r.level = simulated;
                    const io::ToolSpec& tool = scene.tools[static_cast<std::size_t>(active.load())];
                    r.tool = tool.name + " (" +
                             (tool.action == io::ToolAction::cut ? std::string(tool.cut_mode == io::CutMode::remove ? "cut, removing" : "cut, separating")
                              : tool.action == io::ToolAction::wet ? std::string("wet")
                                                                   : std::string("push")) +
                             ")";
                    pictures.publish();
                }
                ++frame;
                frames.fetch_add(1, std::memory_order_relaxed);
                // Simulated time keeps pace with wall time; a late frame does not wait.
                next += std::chrono::duration_cast<clock_type::duration>(std::chrono::duration<double>(dt));
                if (next > clock_type::now()) std::this_thread::sleep_until(next);
                else next = clock_type::now();
            }
        } catch (const std::exception& e) {
            failure = e.what();
            stop = true;
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
    } joiner{stop, simulation, loop};

    // The window, on this thread.
    Orbit orbit{spec, bounds.center(), 2.5 * radius, radius};
    const Orbit home = [&] {
        Orbit o = orbit;
        const render::Camera fitted = render::fit_camera(spec, first.positions, static_cast<double>(options.width) / options.height);
        o.target = fitted.target;
        o.distance = (fitted.eye - fitted.target).norm();
        return o;
    }();
    orbit = home;
    double mouse_x = 0, mouse_y = 0;
    bool show_help = false, use_lod = options.display_triangles > 0, screenshot = false;
    int width = options.width, height = options.height, shots = 0;
    // The tool's point under the cursor, at the depth of where the tool now is.
    render::Window* window_ptr = nullptr;
    auto pointer_at = [&](double x, double y) {
        const render::Camera c = orbit.camera();
        Eigen::Vector3d right, up, forward;
        c.basis(right, up, forward);
        int w = 1, h = 1; // the cursor is in window units (not framebuffer pixels on a scaled display)
        window_ptr->window_size(w, h);
        const double tan_v = std::tan(0.5 * c.fov_y_deg * M_PI / 180.0), tan_h = tan_v * w / h;
        const Eigen::Vector3d ray = (forward + (2.0 * x / w - 1.0) * tan_h * right + (1.0 - 2.0 * y / h) * tan_v * up).normalized();
        const double depth = (pointer.pointed() - c.eye).dot(forward);
        return Eigen::Vector3d(c.eye + ray * (depth / ray.dot(forward)));
    };
    render::InputHandlers input;
    input.key = [&](int key, int) {
        switch (key) {
        case GLFW_KEY_ESCAPE: case GLFW_KEY_Q: window_ptr->close(); break;
        case GLFW_KEY_SPACE: paused = !paused.load(); break;
        case GLFW_KEY_N: step_once = true; break;
        case GLFW_KEY_TAB: active = (active.load() + 1) % static_cast<int>(scene.tools.size()); break;
        case GLFW_KEY_C: show_cage = !show_cage.load(); break;
        case GLFW_KEY_V: show_voxels = !show_voxels.load(); break;
        case GLFW_KEY_L: use_lod = !use_lod; break;
        case GLFW_KEY_S: save_object = true; break;
        case GLFW_KEY_U: undo = true; break;
        case GLFW_KEY_M: toggle_cut_mode = true; break;
        case GLFW_KEY_1: set_action = 0; break;
        case GLFW_KEY_2: set_action = 1; break;
        case GLFW_KEY_3: set_action = 2; break;
        case GLFW_KEY_EQUAL: case GLFW_KEY_KP_ADD: level_change = 1; break;    // coarser: faster
        case GLFW_KEY_MINUS: case GLFW_KEY_KP_SUBTRACT: level_change = -1; break; // finer: more accurate
        case GLFW_KEY_P: screenshot = true; break;
        case GLFW_KEY_R: orbit = home; break;
        case GLFW_KEY_H: case GLFW_KEY_SLASH: show_help = !show_help; break;
        default: break;
        }
    };
    input.move = [&](double x, double y) {
        const double dx = x - mouse_x, dy = y - mouse_y;
        mouse_x = x;
        mouse_y = y;
        if (!window_ptr) return;
        if (window_ptr->button_down(GLFW_MOUSE_BUTTON_LEFT)) pointer.point_at(pointer_at(x, y));
        if (window_ptr->button_down(GLFW_MOUSE_BUTTON_RIGHT)) {
            orbit.spec.yaw_deg -= 0.3 * dx;
            orbit.spec.pitch_deg = std::clamp(orbit.spec.pitch_deg + 0.3 * dy, -89.0, 89.0);
        }
        if (window_ptr->button_down(GLFW_MOUSE_BUTTON_MIDDLE)) {
            Eigen::Vector3d right, up, forward;
            orbit.camera().basis(right, up, forward);
            orbit.target -= (dx * right - dy * up) * orbit.distance * 0.0015;
        }
    };
    input.button = [&](int button, bool down, int) {
        if (button != GLFW_MOUSE_BUTTON_LEFT || !down) return;
        stroke_started = true; // a stroke begins: what U undoes
        pointer.point_at(pointer_at(mouse_x, mouse_y));
    };
    input.scroll = [&](double dy, int mods) {
        if (mods & GLFW_MOD_SHIFT) {
            orbit.distance *= std::pow(0.9, dy);
            return;
        }
        const render::Camera c = orbit.camera();
        pointer.point_at(pointer.pointed() + (c.target - c.eye).normalized() * (-dy * 0.02 * radius));
    };
    render::Window window("VoxSculpt - " + scene_path, options.width, options.height, input);
    window_ptr = &window;
    render::Renderer renderer;
    render::TextOverlay text;
    loop.start();


    std::unique_ptr<render::DisplayLod> lod;
    std::size_t lod_source_triangles = 0;
    std::vector<render::DrawMesh> drawn;
    double rate_time = now_s(), sim_rate = 0, haptic_rate = 0, draw_rate = 0;
    std::uint64_t last_frames = 0, last_ticks = 0, draws = 0;
    bool have_picture = false;
    double first_shown = -1.0; // when the first picture was drawn (--exit-after counts from there)
    while (!window.should_close() && !stop.load()) {
        const bool fresh = pictures.update();
        if (fresh) {
            have_picture = true;
            picture_taken = true;
        }
        window.size(width, height);
        if (width <= 0 || height <= 0) {
            window.present();
            continue;
        }
        if (fresh) { // a new picture: take it (and its lighter copy) once
            const RenderState& state = pictures.read_slot();
            drawn = state.meshes;
            if (!drawn.empty() && state.smooth > 0) { // off the simulation thread
                render::smooth_for_display(drawn.front(), state.smooth);
                render::compute_normals(drawn.front());
            }
            lod_source_triangles = drawn.empty() ? 0 : drawn.front().indices.size() / 3;
            if (use_lod && !drawn.empty() && drawn.front().indices.size() / 3 > options.display_triangles) {
                if (!lod || !lod->fits(drawn.front()))
                    lod = std::make_unique<render::DisplayLod>(drawn.front(), render::lod_cell_mm(drawn.front(), options.display_triangles));
                render::DrawMesh light;
                lod->apply(drawn.front(), light);
                drawn.front() = std::move(light);
            }
        }
        renderer.draw(drawn, orbit.camera(), width, height);
        ++draws;
        const double t = now_s();
        if (t - rate_time >= 1.0) {
            const std::uint64_t f = frames.load(), k = ticks.load();
            sim_rate = static_cast<double>(f - last_frames) / (t - rate_time);
            haptic_rate = static_cast<double>(k - last_ticks) / (t - rate_time);
            draw_rate = static_cast<double>(draws) / (t - rate_time);
            last_frames = f;
            last_ticks = k;
            draws = 0;
            rate_time = t;
        }
        const RenderState* shown = have_picture ? &pictures.read_slot() : nullptr;
        char status[512];
        std::snprintf(status, sizeof status,
                      "simulation %.0f Hz%s   haptics %.0f Hz   drawing %.0f Hz\n%zu elements, level %d   surface %zu triangles%s\ntool %s%s   "
                      "H: keys",
                      sim_rate, paused.load() ? " (paused)" : "", haptic_rate, draw_rate, shown ? shown->elements : 0, shown ? shown->level : level,
                      drawn.empty() ? 0 : drawn.front().indices.size() / 3, use_lod && lod && drawn.front().indices.size() / 3 < lod_source_triangles ? " (display level of detail)" : "",
                      shown ? shown->tool.c_str() : "", show_cage.load() ? "   cage shown" : "");
        text.draw(status, 14, 14, width, height);
        if (show_help) text.draw(key_map, 14, height - 8 * 22 - 14, width, height);
        if (have_picture && first_shown < 0.0) first_shown = t;
        const bool last = options.exit_after_s > 0.0 && first_shown >= 0.0 && t >= first_shown + options.exit_after_s;
        if (screenshot || (last && !options.screenshot.empty())) {
            const std::filesystem::path path = last && !options.screenshot.empty()
                                                   ? std::filesystem::path(options.screenshot)
                                                   : std::filesystem::path(options.out_dir) / ("view_" + std::to_string(++shots) + ".png");
            try {
                render::write_png(path, render::read_pixels(width, height));
                log::info("screenshot: {}", path.string());
            } catch (const InputError& e) {
                if (last) throw; // the screenshot asked for on the command line
                log::warn("no screenshot: {}", e.what());
            }
            screenshot = false;
        }
        window.present();
        if (last) window.close();
    }
    log::info("viewer: last second: simulation {:.0f} Hz, haptics {:.0f} Hz, drawing {:.1f} Hz ({} triangles drawn)", sim_rate, haptic_rate,
              draw_rate, drawn.empty() ? 0 : drawn.front().indices.size() / 3);
    stop = true;
    if (simulation.joinable()) simulation.join(); // before reading what it left
    loop.stop();
    if (!failure.empty()) throw InputError(scene_path + ": the simulation stopped: " + failure);
}

} // namespace vox::view
