#pragma once
// The window of a viewer session, on the calling thread: input (the mouse as the tool's pointer,
// the camera, the keys, queued as requests to the simulation thread), drawing the newest picture
// with its display level of detail, the rates and the key map, screenshots. It never waits for the
// other threads.

#include "haptics/pointer_device.hpp"
#include "render/camera.hpp"
#include "view/view_channels.hpp"
#include "view/view_session.hpp"

#include <functional>
#include <string>

namespace vox::view {

struct WindowSetup {
    std::string title;                ///< the scene file, in the title bar
    ViewOptions options;              ///< size, display triangles, screenshots, exit
    render::CameraSpec camera;        ///< the initial view
    render::DrawMesh first;           ///< the object at rest: the camera is fitted to it
    Eigen::Vector3d centre = Eigen::Vector3d::Zero();
    double radius = 50.0;             ///< of the object, mm
    std::size_t tool_count = 1;       ///< TAB cycles through them
    std::function<double()> now_s;    ///< the session's wall time, s
};

/// Runs the window until it closes (or requests.stop); `on_open` runs once the window exists
/// (the haptic loop starts then). Throws InputError when a screenshot asked for on the command
/// line cannot be written.
void run_window(const WindowSetup& setup, ViewChannels& channels, haptics::PointerDevice& pointer, const std::function<void()>& on_open);

} // namespace vox::view
