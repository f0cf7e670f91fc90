#include "app/commands.hpp"
#include "app/selection_options.hpp"
#include "core/log.hpp"
#include "io/object_import.hpp"

#include <CLI/CLI.hpp>

namespace vox::app {

void add_import_command(CLI::App& app)
{
    struct Args {
        std::string input, output;
        SelectionOptions selection;
        MeshOptions mesh;
    };
    auto args = std::make_shared<Args>();
    CLI::App* cmd = app.add_subcommand("import", "Read a scan or mesh and write its labelled voxels as an OpenVDB file");
    cmd->add_option("input", args->input, "Volume (.inr[.gz] .nii[.gz] .mhd .mha .nrrd .nhdr .vdb) or mesh (.obj .ply .stl .off)")
        ->required();
    cmd->add_option("-o,--output", args->output, "Output .vdb file (int32 labels + index-to-world transform)")->required();
    add_selection_options(*cmd, args->selection);
    add_mesh_options(*cmd, args->mesh);
    cmd->callback([args] {
        require_vdb_extension(args->output);
        const grid::LabelGrid labels = io::import_object(args->input, import_options(args->selection, args->mesh));
        labels.save(args->output);
        std::string histogram;
        for (const auto& [label, n] : labels.label_histogram()) {
            if (!histogram.empty()) histogram += ", ";
            histogram += std::to_string(label) + ": " + std::to_string(n);
        }
        log::info("wrote {}: {} voxels (label: count {})", args->output, labels.active_voxel_count(), histogram);
    });
}

} // namespace vox::app
