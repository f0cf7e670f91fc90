// voxsculpt export: the object's marching-cubes surface as a mesh file in world millimetres, or
// its voxels as a label map on the scan's grid (.seg.nrrd, .nrrd, .nii.gz).

#include "app/commands.hpp"
#include "app/selection_options.hpp"
#include "core/error.hpp"
#include "core/log.hpp"
#include "grid/branched_grid.hpp"
#include "io/mesh_info.hpp"
#include "io/glb_writer.hpp"
#include "io/label_map_writer.hpp"
#include "io/segmentation.hpp"
#include "render/draw_mesh.hpp"
#include "core/label_palette.hpp"
#include "io/mesh_writer.hpp"
#include "io/object_import.hpp"
#include "io/scene_object.hpp"
#include "surface/embedded_surface.hpp"

#include <CLI/CLI.hpp>

namespace vox::app {

void add_export_command(CLI::App& app)
{
    struct Args {
        std::string input, output;
        SelectionOptions selection;
        MeshOptions mesh;
        int smooth = 0;
        int level = 1;
    };
    auto args = std::make_shared<Args>();
    CLI::App* cmd = app.add_subcommand(
        "export", "Write the object's surface (marching cubes on voxel centres) as a mesh, or its voxels as a label map");
    cmd->add_option("input", args->input, "Volume, DICOM folder, segmentation, .vdb or mesh file")->required();
    cmd->add_option("-o,--output", args->output,
                    "Mesh file (.obj, .ply with per-vertex labels, .stl, .off, .glb coloured per label) or label map on the scan's grid "
                    "(.seg.nrrd with segment names and colours, .nrrd, .nii, .nii.gz)")
        ->required();
    add_selection_options(*cmd, args->selection);
    add_mesh_options(*cmd, args->mesh);
    cmd->add_option("--smooth", args->smooth, "Taubin smoothing iterations in rest space (default 0)")
        ->check(CLI::Range(0, 1000));
    cmd->add_option("--level", args->level, "Level of the elements the surface is embedded in (default 1)")
        ->check(CLI::Range(1, 6));
    cmd->callback([args] {
        const bool label_map = io::is_label_map_path(args->output);
        const bool glb = args->output.size() > 4 && args->output.compare(args->output.size() - 4, 4, ".glb") == 0;
        if (!io::is_writable_mesh_path(args->output) && !label_map && !glb)
            throw InputError(args->output + ": the output must end in .obj, .ply, .stl, .off, .glb (a surface) or .seg.nrrd, "
                                            ".nrrd, .nii, .nii.gz (a label map)");
        const grid::LabelGrid labels = io::import_object(args->input, import_options(args->selection, args->mesh));
        if (label_map) {
            io::write_label_map(labels, args->output);
            log::info("wrote {}: {} voxels", args->output, labels.active_voxel_count());
            return;
        }
        const io::MaterialTable table = io::default_material_table();
        const grid::BranchedGrid g(grid::FineVoxels(labels, [&](std::int32_t l) { return table.index_of(l); }),
                                   table.materials, args->level);
        surface::EmbeddedSurface s(g, args->level);
        if (args->smooth > 0) s.smooth(g, args->smooth);
        const surface::SurfaceMesh m = s.mesh(g);
        if (glb) {
            std::map<std::int32_t, io::Segment> segments; // a segmentation's own colours and names
            for (auto& [label, segment] : io::segments_of(labels)) segments[label] = segment;
            io::write_glb(
                args->output, m.positions, m.triangles, m.labels,
                [&](std::int32_t l) { return segments.count(l) ? segments[l].color : label_color(l); },
                [&](std::int32_t l) { return segments.count(l) ? segments[l].name : "label " + std::to_string(l); });
        } else {
            io::write_mesh(args->output, m.positions, m.triangles, m.labels);
        }
        io::TriangleMesh t{m.positions, m.triangles};
        const io::MeshInfo info = io::mesh_info(t);
        log::info("wrote {}: {} triangles, {} vertices, {}, enclosed volume {:.6g} mm^3", args->output,
                  m.triangles.size(), m.positions.size(), info.closed ? "closed" : "NOT closed",
                  info.enclosed_volume_mm3);
    });
}

} // namespace vox::app
