#include "app/view_session.hpp"

#include "app/scene_pictures.hpp"
#include "app/scene_simulation.hpp"
#include "app/tool_session.hpp"
#include "core/error.hpp"
#include "core/log.hpp"
#include "cut/surface_contact.hpp"
#include "haptics/coupled_tool.hpp"
#include "haptics/haptic_loop.hpp"
#include "haptics/pointer_device.hpp"
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

namespace vox::app {
namespace {

using clock_type = std::chrono::steady_clock;

/// What the simulation thread shows the window.
struct RenderState {
    std::vector<render::DrawMesh> meshes; ///< the surface first, then the tools (and the cage)
    double t_s = 0.0;
    std::size_t elements = 0;
};

/// The tool the haptic thread moved, and where.
struct ProxyPose {
    int tool = 0;
    contact::PlacedShape pose;
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

const char* const key_map = "mouse left: move the tool in the view plane    wheel: tool nearer / farther\n"
                            "mouse right: orbit    middle: pan    shift + wheel: zoom    R: reset the view\n"
                            "TAB: next tool    SPACE: pause / run    N: one step while paused\n"
                            "C: element cage    L: full surface / display level of detail\n"
                            "S: save the surface (.obj)    P: screenshot (.png)    H or ?: this help    Q, ESC: quit";

} // namespace

void run_view(const std::string& scene_path, const ViewOptions& options)
{
    const io::Scene loaded = io::load_scene(scene_path);
    if (loaded.tools.empty()) throw loaded.error("tools", "the viewer needs at least one tool to sculpt with");
    // The user moves the tools: the script does not.
    io::Scene scene = loaded;
    scene.script.clear();
    render::CameraSpec spec = render::parse_camera(options.camera);
    spec.up = scene_up(scene);
    const grid::LabelGrid labels = io::load_scene_object(scene);
    const int level = std::max(scene.object.levels, 1);
    grid::BranchedGrid g = build_scene_grid(scene, labels, level);
    SceneSimulation sim(scene, g, level);
    ToolSession tools(scene);

    // Where the first tool starts: where the scene's script puts it, else above the object.
    render::DrawMesh first = surface_picture(sim, 0);
    Eigen::AlignedBox3d bounds;
    bounds.setEmpty();
    for (const std::uint32_t i : first.indices) bounds.extend(first.positions[i].cast<double>());
    const double radius = 0.5 * bounds.diagonal().norm();
    const io::ToolPose scripted = io::tool_pose(loaded, 0, 0.0);
    const Eigen::Vector3d start = scripted.placed ? scripted.position_mm : Eigen::Vector3d(bounds.center() + (radius + 10.0) * spec.up);
    haptics::PointerDevice pointer(start, scripted.placed ? scripted.orientation : Eigen::Quaterniond::Identity());

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
    std::atomic<bool> stop{false}, paused{false}, step_once{false}, show_cage{false}, save_surface{false}, picture_taken{true};
    std::atomic<std::uint64_t> ticks{0}, frames{0};
    const auto t0 = clock_type::now();
    auto now_s = [&t0] { return std::chrono::duration<double>(clock_type::now() - t0).count(); };

    haptics::HapticLoop loop(
        pointer,
        [&](const haptics::DeviceState& s, double& age) -> Eigen::Vector3d {
            snapshots.update();
            const contact::SurfacePoints& surface = snapshots.read_slot();
            age = now_s() - surface.t_s;
            const int k = active.load(std::memory_order_relaxed);
            const Eigen::Vector3d f = coupled[static_cast<std::size_t>(k)]->update(s, surface, 1e-3);
            proxies.write_slot() = {k, coupled[static_cast<std::size_t>(k)]->proxy()};
            proxies.publish();
            ticks.fetch_add(1, std::memory_order_relaxed);
            return f;
        },
        haptics::SafetySettings{});

    // The simulation thread.
    std::string failure;
    std::thread simulation([&] {
        try {
            const tbb::global_control one_thread(tbb::global_control::max_allowed_parallelism, 1); // the other core is the loop's
            const double dt = scene.solver.dt_s;
            int driven = -1;
            contact::PlacedShape pose{&tools.shape(0), start, Eigen::Quaterniond::Identity()};
            std::uint64_t frame = 0;
            auto next = clock_type::now();
            while (!stop.load()) {
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
                }
                if (driven >= 0) tools.drive(static_cast<std::size_t>(driven), pose.position, pose.orientation);
                const ToolFrameStats t = tools.frame(sim, g, static_cast<double>(frame + 1) * dt, dt);
                if (!t.hold_object) sim.solver().step();
                contact::SurfacePoints& out = snapshots.write_slot();
                const double margin = scene.tools[static_cast<std::size_t>(std::max(driven, 0))].push_margin_mm;
                cut::sample_surface(sim.surface(), sim.solver().positions(), pose.world_bounds(margin + 5.0), out);
                out.t_s = now_s();
                snapshots.publish();
                if (save_surface.exchange(false)) {
                    const std::filesystem::path path = std::filesystem::path(options.out_dir) / "view_surface.obj";
                    const surface::SurfaceMesh m = sim.surface().mesh(sim.solver().positions());
                    io::write_mesh(path.string(), m.positions, m.triangles, m.labels);
                    log::info("saved the surface to {} ({} triangles)", path.string(), m.triangles.size());
                }
                if (picture_taken.exchange(false)) { // the window has the last one: make the next
                    RenderState& r = pictures.write_slot();
                    r.meshes.clear();
                    r.meshes.push_back(surface_picture(sim, options.smooth));
                    for (std::size_t k = 0; k < scene.tools.size(); ++k) add_tool_drawings(tools.placed(k), scene.tools[k].push_margin_mm, r.meshes);
                    if (show_cage.load()) r.meshes.push_back(element_cage(sim));
                    r.t_s = static_cast<double>(frame + 1) * dt;
                    r.elements = sim.model().elements().size();
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
    auto pointer_at = [&](double x, double y) {
        const render::Camera c = orbit.camera();
        const Eigen::Vector3d forward = (c.target - c.eye).normalized(), right = forward.cross(c.up).normalized(), up = right.cross(forward);
        const double tan_v = std::tan(0.5 * c.fov_y_deg * M_PI / 180.0), tan_h = tan_v * width / height;
        const Eigen::Vector3d ray = (forward + (2.0 * x / width - 1.0) * tan_h * right + (1.0 - 2.0 * y / height) * tan_v * up).normalized();
        const double depth = (pointer.pointed() - c.eye).dot(forward);
        return Eigen::Vector3d(c.eye + ray * (depth / ray.dot(forward)));
    };
    render::InputHandlers input;
    render::Window* window_ptr = nullptr;
    input.key = [&](int key, int) {
        switch (key) {
        case GLFW_KEY_ESCAPE: case GLFW_KEY_Q: window_ptr->close(); break;
        case GLFW_KEY_SPACE: paused = !paused.load(); break;
        case GLFW_KEY_N: step_once = true; break;
        case GLFW_KEY_TAB: active = (active.load() + 1) % static_cast<int>(scene.tools.size()); break;
        case GLFW_KEY_C: show_cage = !show_cage.load(); break;
        case GLFW_KEY_L: use_lod = !use_lod; break;
        case GLFW_KEY_S: save_surface = true; break;
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
            const render::Camera c = orbit.camera();
            const Eigen::Vector3d forward = (c.target - c.eye).normalized(), right = forward.cross(c.up).normalized(), up = right.cross(forward);
            orbit.target -= (dx * right - dy * up) * orbit.distance * 0.0015;
        }
    };
    input.button = [&](int button, bool down, int) {
        if (button == GLFW_MOUSE_BUTTON_LEFT && down) pointer.point_at(pointer_at(mouse_x, mouse_y));
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
    log::info("viewer: {} ({} elements at level {}), tools: {}; press H for the keys", scene_path, sim.model().elements().size(), level,
              scene.tools.size());

    std::unique_ptr<render::DisplayLod> lod;
    std::vector<render::DrawMesh> drawn;
    double rate_time = now_s(), sim_rate = 0, haptic_rate = 0, draw_rate = 0;
    std::uint64_t last_frames = 0, last_ticks = 0, draws = 0;
    bool have_picture = false;
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
        const io::ToolSpec& tool = scene.tools[static_cast<std::size_t>(active.load())];
        char status[512];
        std::snprintf(status, sizeof status,
                      "simulation %.0f Hz%s   haptics %.0f Hz   drawing %.0f Hz\n%zu elements, level %d   surface %zu triangles%s\ntool %s (%s)%s   "
                      "H: keys",
                      sim_rate, paused.load() ? " (paused)" : "", haptic_rate, draw_rate, have_picture ? pictures.read_slot().elements : 0, level,
                      drawn.empty() ? 0 : drawn.front().indices.size() / 3, use_lod && lod ? " (display level of detail)" : "", tool.name.c_str(),
                      tool.action == io::ToolAction::cut ? "cut" : tool.action == io::ToolAction::wet ? "wet" : "push",
                      show_cage.load() ? "   cage shown" : "");
        text.draw(status, 14, 14, width, height);
        if (show_help) text.draw(key_map, 14, height - 110, width, height);
        const bool last = options.exit_after_s > 0.0 && t >= options.exit_after_s;
        if (screenshot || (last && !options.screenshot.empty())) {
            const std::filesystem::path path = last && !options.screenshot.empty()
                                                   ? std::filesystem::path(options.screenshot)
                                                   : std::filesystem::path(options.out_dir) / ("view_" + std::to_string(++shots) + ".png");
            render::write_png(path, render::read_pixels(width, height));
            log::info("screenshot: {}", path.string());
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

} // namespace vox::app
