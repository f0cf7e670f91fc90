#pragma once
// voxsculpt view: interactive sculpting in a window. Three threads, as in a live session:
//  - the haptic thread: the 1 kHz loop reads each device (the mouse and keyboard as a 3-DoF
//    pointer when no haptic device is present; a 6-DoF controller; the scene's script for a tool),
//    couples its tool to it against the newest surface snapshot near that tool, publishes the
//    tool's pose;
//  - the simulation thread: puts the tool there, lets it push, cut and wet, steps the FEM paced to
//    wall time, publishes the surface near the tool (for the haptic thread) and the whole surface
//    with the tools (for the window);
//  - this thread: the window, input, camera and drawing. Neither other thread ever waits for it:
//    they share triple buffers and atomics only.

#include <string>
#include <vector>

namespace vox::view {

struct ViewOptions {
    std::string camera = "iso";
    int width = 1280, height = 800;
    int smooth = 4;                       ///< display smoothing (Taubin iterations)
    std::size_t display_triangles = 150000; ///< draw a clustered copy above this many triangles (0: always the full surface)
    double exit_after_s = 0.0;            ///< > 0: close by itself this long after the first picture (tests, recordings)
    std::string screenshot;               ///< with exit_after_s: the last picture, PNG
    std::string out_dir = ".";            ///< where screenshots, saved surfaces and the session journal go
    std::string resume;                   ///< a session journal to start from (empty: offer the last one, if any)
    /// One entry per device, each driving its own tool: "auto" (a 6-DoF controller when one can
    /// be opened, else the mouse), "mouse", "hid" (a controller, or an error saying why there is
    /// none), "script" (the tool follows its script, in simulated time).
    std::vector<std::string> devices = {"auto"};
    /// The tool each device drives, by name, in the same order (empty: one device, the first
    /// tool, TAB moves it to the next).
    std::vector<std::string> tools;
    /// "dbg", "isxfem" or "shape_matching": simulate with this method instead of the scene's solver.type (empty: the scene's).
    std::string solver;
};

/// Runs the viewer on `scene_path` until the window closes. Throws InputError for a bad scene or
/// option, render::NoOpenGL without a display.
void run_view(const std::string& scene_path, const ViewOptions& options);

} // namespace vox::view
