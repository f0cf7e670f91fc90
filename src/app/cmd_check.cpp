// voxsculpt check: reads a scene, builds its object and reports what a run would simulate, so a
// scene can be validated before it is run.

#include "app/commands.hpp"
#include "core/log.hpp"
#include "grid/coarse_cells.hpp"
#include "io/scene.hpp"
#include "io/scene_object.hpp"

#include <CLI/CLI.hpp>

#include <cstdio>

namespace vox::app {

void add_check_command(CLI::App& app)
{
    auto path = std::make_shared<std::string>();
    CLI::App* cmd = app.add_subcommand("check", "Validate a scene file and build its object; print a summary");
    cmd->add_option("scene", *path, "Scene file (.json, see docs/scene-format.md)")->required();
    cmd->callback([path] {
        const io::Scene scene = io::load_scene(*path);
        const grid::LabelGrid labels = io::load_scene_object(scene);
        io::check_constraints(scene, labels);
        const io::MaterialCoverage cover = io::material_coverage(scene, labels);
        for (std::int32_t l : cover.unused)
            log::warn("{}: materials.labels.{} names a label the object does not hold", *path, l);

        const int level = scene.object.levels;
        const Eigen::Vector3d voxel = labels.voxel_size();
        std::printf("scene: %s\n", path->c_str());
        std::printf("object: %s, %llu voxels of %.6g x %.6g x %.6g mm\n", labels.metadata("source").c_str(),
                    static_cast<unsigned long long>(labels.active_voxel_count()), voxel.x(), voxel.y(), voxel.z());
        for (const auto& [label, n] : labels.label_histogram()) {
            const io::Material& m = scene.material(label);
            std::printf("  label %d: %llu voxels, E = %g Pa, nu = %g, rho = %g kg/m^3\n", label,
                        static_cast<unsigned long long>(n), m.youngs_modulus_pa, m.poisson_ratio, m.density_kg_m3);
        }
        if (scene.object.auto_levels) {
            if (scene.object.step_budget_ms)
                std::printf("level: auto, the finest whose step fits %g ms\n", *scene.object.step_budget_ms);
            else
                std::printf("level: auto, the coarsest within %g %% of the next finer level\n", 100 * scene.object.max_error.value_or(0.0));
        } else {
            std::printf("level %d: %zu occupied cells of %d^3 voxels\n", level, grid::occupied_cells(labels, level).size(),
                        1 << level);
        }
        std::printf("solver: %s, dt %g s, CG tolerance %g, at most %d iterations\n",
                    scene.solver.type == io::SolverType::dbg ? "dbg" : "isxfem", scene.solver.dt_s,
                    scene.solver.cg_tolerance, scene.solver.cg_max_iterations);
        std::printf("constraints: %zu, tools: %zu, script: %zu key frames", scene.constraints.size(), scene.tools.size(),
                    scene.script.size());
        if (!scene.script.empty()) std::printf(" over %g s", scene.script.back().t_s - scene.script.front().t_s);
        std::printf("\noutput: %s\n", scene.output.dir.string().c_str());
    });
}

} // namespace vox::app
