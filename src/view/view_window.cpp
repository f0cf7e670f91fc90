#include "view/view_window.hpp"

#include "core/error.hpp"
#include "core/log.hpp"
#include "render/display_lod.hpp"
#include "render/text_overlay.hpp"
#include "render/window.hpp"

#include <GLFW/glfw3.h>

#include <algorithm>
#include <cmath>
#include <memory>

namespace vox::view {
namespace {

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
                            "J: resume the earlier session its journal offers\n"
                            "SPACE: pause / run   N: one step while paused\n"
                            "+ / -: coarser / finer level (deformation restarts)\n"
                            "C: element cage   V: the fine voxels   L: level of detail\n"
                            "S: save (.obj, .vdb, .seg.nrrd, .nii.gz)   P: screenshot   H, ?: help   Q, ESC: quit";

} // namespace

void run_window(const WindowSetup& setup, ViewChannels& ch, haptics::PointerDevice& pointer, const std::function<void()>& on_open)
{
    ViewRequests& rq = ch.requests;
    auto now_s = setup.now_s;
    // The window, on this thread.
    Orbit orbit{setup.camera, setup.centre, 2.5 * setup.radius, setup.radius};
    const Orbit home = [&] {
        Orbit o = orbit;
        const render::Camera fitted = render::fit_camera(setup.camera, setup.first.positions, static_cast<double>(setup.options.width) / setup.options.height);
        o.target = fitted.target;
        o.distance = (fitted.eye - fitted.target).norm();
        return o;
    }();
    orbit = home;
    double mouse_x = 0, mouse_y = 0;
    bool show_help = false, use_lod = setup.options.display_triangles > 0, screenshot = false;
    int width = setup.options.width, height = setup.options.height, shots = 0;
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
        case GLFW_KEY_SPACE: rq.paused = !rq.paused.load(); break;
        case GLFW_KEY_N: rq.step_once = true; break;
        case GLFW_KEY_TAB: rq.active = (rq.active.load() + 1) % static_cast<int>(setup.tool_count); break;
        case GLFW_KEY_C: rq.show_cage = !rq.show_cage.load(); break;
        case GLFW_KEY_V: rq.show_voxels = !rq.show_voxels.load(); break;
        case GLFW_KEY_L: use_lod = !use_lod; break;
        case GLFW_KEY_S: rq.save_object = true; break;
        case GLFW_KEY_U: rq.undo = true; break;
        case GLFW_KEY_J: rq.resume = true; break;
        case GLFW_KEY_M: rq.toggle_cut_mode = true; break;
        case GLFW_KEY_1: rq.set_action = 0; break;
        case GLFW_KEY_2: rq.set_action = 1; break;
        case GLFW_KEY_3: rq.set_action = 2; break;
        case GLFW_KEY_EQUAL: case GLFW_KEY_KP_ADD: rq.level_change = 1; break;    // coarser: faster
        case GLFW_KEY_MINUS: case GLFW_KEY_KP_SUBTRACT: rq.level_change = -1; break; // finer: more accurate
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
        if (button != GLFW_MOUSE_BUTTON_LEFT) return;
        if (!down) {
            rq.stroke_ended = true; // the stroke's cuts go to the session journal
            return;
        }
        rq.stroke_started = true; // a stroke begins: what U undoes
        pointer.point_at(pointer_at(mouse_x, mouse_y));
    };
    input.scroll = [&](double dy, int mods) {
        if (mods & GLFW_MOD_SHIFT) {
            orbit.distance *= std::pow(0.9, dy);
            return;
        }
        const render::Camera c = orbit.camera();
        pointer.point_at(pointer.pointed() + (c.target - c.eye).normalized() * (-dy * 0.02 * setup.radius));
    };
    render::Window window("VoxSculpt - " + setup.title, setup.options.width, setup.options.height, input);
    window_ptr = &window;
    render::Renderer renderer;
    render::TextOverlay text;
    on_open();


    std::unique_ptr<render::DisplayLod> lod;
    std::size_t lod_source_triangles = 0;
    std::vector<render::DrawMesh> drawn;
    double rate_time = now_s(), sim_rate = 0, haptic_rate = 0, draw_rate = 0;
    std::uint64_t last_frames = 0, last_ticks = 0, draws = 0;
    bool have_picture = false;
    double first_shown = -1.0; // when the first picture was drawn (--exit-after counts from there)
    while (!window.should_close() && !rq.stop.load()) {
        const bool fresh = ch.pictures.update();
        if (fresh) {
            have_picture = true;
            rq.picture_taken = true;
        }
        window.size(width, height);
        if (width <= 0 || height <= 0) {
            window.present();
            continue;
        }
        if (fresh) { // a new picture: take it (and its lighter copy) once
            const RenderState& state = ch.pictures.read_slot();
            drawn = state.meshes;
            if (!drawn.empty() && state.smooth > 0) { // off the simulation thread
                render::smooth_for_display(drawn.front(), state.smooth);
                render::compute_normals(drawn.front());
            }
            lod_source_triangles = drawn.empty() ? 0 : drawn.front().indices.size() / 3;
            if (use_lod && !drawn.empty() && drawn.front().indices.size() / 3 > setup.options.display_triangles) {
                if (!lod || !lod->fits(drawn.front()))
                    lod = std::make_unique<render::DisplayLod>(drawn.front(), render::lod_cell_mm(drawn.front(), setup.options.display_triangles));
                render::DrawMesh light;
                lod->apply(drawn.front(), light);
                drawn.front() = std::move(light);
            }
        }
        renderer.draw(drawn, orbit.camera(), width, height);
        ++draws;
        const double t = now_s();
        if (t - rate_time >= 1.0) {
            const std::uint64_t f = rq.frames.load(), k = rq.ticks.load();
            sim_rate = static_cast<double>(f - last_frames) / (t - rate_time);
            haptic_rate = static_cast<double>(k - last_ticks) / (t - rate_time);
            draw_rate = static_cast<double>(draws) / (t - rate_time);
            last_frames = f;
            last_ticks = k;
            draws = 0;
            rate_time = t;
        }
        const RenderState* shown = have_picture ? &ch.pictures.read_slot() : nullptr;
        char status[512];
        std::snprintf(status, sizeof status,
                      "simulation %.0f Hz%s   haptics %.0f Hz   drawing %.0f Hz\n%s   surface %zu triangles%s\ntool %s%s   "
                      "H: keys",
                      sim_rate, rq.paused.load() ? " (paused)" : "", haptic_rate, draw_rate, shown ? shown->model.c_str() : "",
                      drawn.empty() ? 0 : drawn.front().indices.size() / 3, use_lod && lod && drawn.front().indices.size() / 3 < lod_source_triangles ? " (display level of detail)" : "",
                      shown ? shown->tool.c_str() : "", rq.show_cage.load() ? "   cage shown" : "");
        text.draw(status, 14, 14, width, height);
        if (shown && !shown->notice.empty()) text.draw(shown->notice, 14, 14 + 4 * 22, width, height);
        if (show_help) text.draw(key_map, 14, height - 9 * 22 - 14, width, height);
        if (have_picture && first_shown < 0.0) first_shown = t;
        const bool last = setup.options.exit_after_s > 0.0 && first_shown >= 0.0 && t >= first_shown + setup.options.exit_after_s;
        if (screenshot || (last && !setup.options.screenshot.empty())) {
            const std::filesystem::path path = last && !setup.options.screenshot.empty()
                                                   ? std::filesystem::path(setup.options.screenshot)
                                                   : std::filesystem::path(setup.options.out_dir) / ("view_" + std::to_string(++shots) + ".png");
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
}

} // namespace vox::view
