// voxsculpt grid: builds the branched grid of a volume or scene and reports every level.

#include "app/commands.hpp"
#include "app/selection_options.hpp"
#include "core/error.hpp"
#include "grid/branched_grid.hpp"
#include "io/object_import.hpp"
#include "io/scene.hpp"
#include "io/scene_object.hpp"

#include <CLI/CLI.hpp>
#include <nlohmann/json.hpp>

#include <cstdio>
#include <iostream>
#include <optional>

namespace vox::app {
namespace {

nlohmann::json level_json(int level, const grid::LevelStats& s)
{
    return {{"level", level},
            {"cells", s.cells},
            {"elements", s.elements},
            {"branched_extra", s.elements - s.cells},
            {"nodes", s.nodes},
            {"condensation_steps_direct", s.condensation_steps_direct},
            {"condensation_steps_recursive", s.condensation_steps_recursive},
            {"build_ms", s.build_ms},
            {"peak_memory_mb", static_cast<double>(s.peak_memory_bytes) / (1 << 20)}};
}

} // namespace

void add_grid_command(CLI::App& app)
{
    struct Args {
        std::string input;
        SelectionOptions selection;
        MeshOptions mesh;
        std::optional<int> levels;
        bool as_json = false;
    };
    auto args = std::make_shared<Args>();
    CLI::App* cmd = app.add_subcommand("grid", "Build the branched grid of a volume or scene and report each level");
    cmd->add_option("input", args->input, "Volume, .vdb, mesh, or scene (.json)")->required();
    add_selection_options(*cmd, args->selection);
    add_mesh_options(*cmd, args->mesh);
    cmd->add_option("--levels", args->levels, "Build levels 0 .. L (0..6; default: the scene's level, else 3)")
        ->check(CLI::Range(0, 6));
    cmd->add_flag("--json", args->as_json, "Print JSON instead of a table");
    cmd->callback([args] {
        const bool is_scene = args->input.size() > 5 && args->input.compare(args->input.size() - 5, 5, ".json") == 0;
        std::optional<grid::LabelGrid> labels;
        io::MaterialTable table = io::default_material_table();
        int levels = args->levels.value_or(3);
        if (is_scene) {
            if (!args->selection.to_selection().empty() || args->mesh.voxel_mm || args->mesh.mm_per_unit != 1.0)
                throw InputError("--label, --threshold, --voxel-size and --scale do not apply to a scene (its object "
                                 "says what it selects)");
            const io::Scene scene = io::load_scene(args->input);
            labels.emplace(io::load_scene_object(scene));
            table = io::material_table(scene);
            levels = args->levels.value_or(scene.object.levels);
        } else {
            labels.emplace(io::import_object(args->input, import_options(args->selection, args->mesh)));
        }
        const grid::BranchedGrid g(grid::FineVoxels(*labels, [&](std::int32_t l) { return table.index_of(l); }),
                                   table.materials, levels, {.level0_nodes = true});

        nlohmann::json j{{"input", args->input},
                         {"selected_voxels", g.voxels().alive_count()},
                         {"total_mass_kg", g.total_mass_kg()},
                         {"levels", nlohmann::json::array()}};
        j["levels"].push_back(level_json(0, g.level0_stats()));
        for (int l = 1; l <= levels; ++l) j["levels"].push_back(level_json(l, g.level(l).stats));
        if (args->as_json) {
            std::cout << j.dump(2) << '\n';
            return;
        }
        std::printf("%s: %llu voxels, %.6g kg\n", args->input.c_str(),
                    static_cast<unsigned long long>(g.voxels().alive_count()), g.total_mass_kg());
        std::printf("%5s %10s %10s %9s %10s %12s %12s %9s %8s\n", "level", "cells", "elements", "branched", "nodes",
                    "steps_direct", "steps_recurs", "build_ms", "peak_MB");
        for (const auto& lj : j["levels"])
            std::printf("%5d %10llu %10llu %9llu %10llu %12llu %12llu %9.1f %8.0f\n", lj["level"].get<int>(),
                        lj["cells"].get<unsigned long long>(), lj["elements"].get<unsigned long long>(),
                        lj["branched_extra"].get<unsigned long long>(), lj["nodes"].get<unsigned long long>(),
                        lj["condensation_steps_direct"].get<unsigned long long>(),
                        lj["condensation_steps_recursive"].get<unsigned long long>(), lj["build_ms"].get<double>(),
                        lj["peak_memory_mb"].get<double>());
    });
}

} // namespace vox::app
