// voxsculpt render: one picture, without a display. The input is a scene (the object at rest
// with its tools where the script places them at t = 0), a mesh file (as it is: a final.obj of a
// run, say), or a volume of any format `import` reads (its marching-cubes surface, coloured by
// label).

#include "app/commands.hpp"
#include "view/scene_pictures.hpp"
#include "sim/method_factory.hpp"
#include "sim/tool_policy.hpp"
#include "app/selection_options.hpp"
#include "core/error.hpp"
#include "core/log.hpp"
#include "io/mesh.hpp"
#include "io/object_import.hpp"
#include "io/segmentation.hpp"
#include "io/scene.hpp"
#include "io/scene_object.hpp"
#include "io/tool_script.hpp"

#include <CLI/CLI.hpp>

namespace vox::app {

using view::PictureOptions;
using view::add_obstacle_drawings;
using view::ScenePictures;
using view::add_tool_drawings;
using view::parse_size;
using view::scene_up;
using view::surface_drawing;
using view::surface_picture;
namespace {

bool ends_with(const std::string& s, const std::string& suffix)
{
    return s.size() >= suffix.size() && s.compare(s.size() - suffix.size(), suffix.size(), suffix) == 0;
}

} // namespace

void add_render_command(CLI::App& app)
{
    struct Args {
        std::string input, out, camera = "iso", size = "960x720";
        int smooth = 30;
        SelectionOptions selection;
    };
    auto args = std::make_shared<Args>();
    CLI::App* cmd = app.add_subcommand("render", "Draw a scene, mesh or volume to a PNG file, headless");
    cmd->add_option("input", args->input, "Scene (.json), mesh (.obj .ply .stl .off) or volume (.vdb .nii .inr .mha .nrrd ...)")->required();
    cmd->add_option("--out", args->out, "PNG file to write")->required();
    cmd->add_option("--camera", args->camera,
                    "iso (default), front, back, left, right, top, bottom, or YAW,PITCH in degrees; add \",ortho\" for an orthographic view");
    cmd->add_option("--size", args->size, "WIDTHxHEIGHT in pixels (default 960x720)");
    cmd->add_option("--smooth", args->smooth, "Display smoothing of the surface, Taubin iterations (default 30; 0 shows the voxel steps)")
        ->check(CLI::Range(0, 200));
    add_selection_options(*cmd, args->selection);
    cmd->callback([args] {
        if (!ends_with(args->out, ".png")) throw InputError(args->out + ": the picture must be a .png file");
        PictureOptions options;
        options.camera = render::parse_camera(args->camera);
        std::tie(options.width, options.height) = parse_size(args->size);
        options.smooth = args->smooth;
        std::vector<render::DrawMesh> meshes;
        if (ends_with(args->input, ".json")) {
            const io::Scene scene = io::load_scene(args->input);
            options.camera.up = scene_up(scene);
            // The scene's object as its method starts it: the same picture as a run's first.
            const sim::OpenedMethod opened = sim::open_method(scene, std::make_shared<const grid::LabelGrid>(io::load_scene_object(scene)));
            meshes.push_back(surface_picture(*opened.method, options.smooth, scene.object.label_colors));
            const sim::ToolPolicy tools(scene);
            for (std::size_t k = 0; k < scene.tools.size(); ++k) {
                const io::ToolPose pose = io::tool_pose(scene, k, 0.0);
                if (pose.placed) add_tool_drawings({&tools.shape(k), pose.position_mm, pose.orientation}, scene.tools[k].push_margin_mm, meshes);
            }
            add_obstacle_drawings(opened.method->obstacles(), meshes.front(), meshes);
        } else if (io::is_mesh_path(args->input)) {
            const io::TriangleMesh m = io::read_mesh(args->input);
            meshes.push_back(surface_drawing({m.vertices, m.triangles, {}}, options.smooth));
        } else {
            const grid::LabelGrid labels = io::import_object(args->input, import_options(args->selection, MeshOptions{}));
            const io::MaterialTable table = io::default_material_table();
            const grid::BranchedGrid g(grid::FineVoxels(labels, [&](std::int32_t l) { return table.index_of(l); }), table.materials, 1);
            view::LabelColors colors; // a segmentation's own
            for (const auto& [label, segment] : io::segments_of(labels)) colors[label] = segment.color;
            meshes.push_back(surface_drawing(surface::EmbeddedSurface(g, 1).mesh(g), options.smooth, colors));
        }
        ScenePictures pictures(options);
        pictures.write(args->out, meshes);
        log::info("wrote {} ({} x {} pixels, {})", args->out, options.width, options.height, pictures.context_description());
    });
}

} // namespace vox::app
