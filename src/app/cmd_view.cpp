// voxsculpt view: sculpt a scene interactively in a window (see view/view_session.hpp).

#include "app/commands.hpp"
#include "view/scene_pictures.hpp"
#include "view/view_session.hpp"
#include "core/error.hpp"

#include <CLI/CLI.hpp>

namespace vox::app {

using view::ViewOptions;
using view::parse_size;
using view::run_view;

void add_view_command(CLI::App& app)
{
    struct Args {
        std::string scene, size = "1280x800";
        ViewOptions options;
    };
    auto args = std::make_shared<Args>();
    CLI::App* cmd = app.add_subcommand("view", "Sculpt a scene interactively in a window (mouse and keyboard, or a haptic device)");
    cmd->add_option("scene", args->scene, "Scene file (.json, see docs/scene-format.md); its script is ignored: you move the tools")->required();
    cmd->add_option("--camera", args->options.camera, "Initial view (as for `voxsculpt render`; default iso)");
    cmd->add_option("--size", args->size, "Window size, WIDTHxHEIGHT (default 1280x800)");
    cmd->add_option("--smooth", args->options.smooth, "Display smoothing of the surface, Taubin iterations (default 4)")->check(CLI::Range(0, 200));
    cmd->add_option("--display-triangles", args->options.display_triangles,
                    "Draw a clustered copy of surfaces with more triangles than this (default 150000; 0: always the full surface)");
    cmd->add_option("--exit-after", args->options.exit_after_s, "Close by itself this many seconds after the first picture (0: when you close it)")
        ->check(CLI::NonNegativeNumber);
    cmd->add_option("--screenshot", args->options.screenshot, "With --exit-after: write the last picture to this PNG file");
    cmd->add_option("--device", args->options.devices,
                    "What drives a tool: auto (a 6-DoF controller if one can be opened, else the mouse; default), mouse, hid, "
                    "openhaptics or forcedimension (force-feedback devices, docs/devices.md), or script (the tool follows its script). "
                    "Once per device, each with its --tool")
        ->check(CLI::IsMember({"auto", "mouse", "hid", "openhaptics", "forcedimension", "script"}));
    cmd->add_option("--tool", args->options.tools,
                    "The tool a device drives, once per --device in the same order (default, one device: the scene's first tool; TAB moves it)");
    cmd->add_option("--solver", args->options.solver, "Simulate with this method instead of the scene's solver.type: dbg, isxfem or shape_matching")
        ->check(CLI::IsMember({"dbg", "isxfem", "shape_matching"}));
    cmd->add_option("--out", args->options.out_dir,
                    "Folder for screenshots (P), saved surfaces (S) and the session journal SCENE.journal (default: the current folder)");
    cmd->add_option("--resume", args->options.resume,
                    "Start from the last stroke of this session journal (docs/journal.md)");
    cmd->callback([args] {
        std::tie(args->options.width, args->options.height) = parse_size(args->size);
        if (!args->options.screenshot.empty() && args->options.exit_after_s <= 0.0)
            throw InputError("--screenshot: give --exit-after too (the picture is taken when the viewer closes by itself)");
        run_view(args->scene, args->options);
    });
}

} // namespace vox::app
