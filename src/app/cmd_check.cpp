// voxsculpt check: reads a scene, builds its object and reports what a run would simulate, so a
// scene can be validated before it is run.

#include "app/commands.hpp"
#include "core/log.hpp"
#include "grid/coarse_cells.hpp"
#include "io/scene.hpp"
#include "io/piece_selection.hpp"
#include "io/scene_object.hpp"
#include "sim/dbg_simulation.hpp"
#include "sim/mixed_region.hpp"
#include "sim/obstacles.hpp"

#include <CLI/CLI.hpp>

#include <algorithm>
#include <cstdio>
#include <string>
#include <vector>

namespace vox::app {
namespace {

const char* unheld_text(io::UnheldPieces u)
{
    switch (u) {
    case io::UnheldPieces::hold: return "held in place (\"unheld_pieces\": \"hold\", the default)";
    case io::UnheldPieces::fall: return "free to fall (\"unheld_pieces\": \"fall\")";
    case io::UnheldPieces::leave_out: return "left out (\"unheld_pieces\": \"leave_out\")";
    case io::UnheldPieces::rigid: return "moved as rigid bodies (\"unheld_pieces\": \"rigid\")";
    }
    return "";
}

/// The object's pieces, largest first, each with whether a constraint box reaches it; a warning
/// naming the pieces nothing holds.
void list_pieces(const io::Scene& scene, const grid::LabelGrid& labels, const std::string& path)
{
    const grid::VoxelPieces pieces(labels);
    const std::vector<bool> held = io::pieces_in_boxes(labels, pieces, scene.object.select.pieces.held_boxes);
    constexpr std::size_t listed = 10;
    std::printf("pieces: %zu (voxels joined through faces), largest first\n", pieces.size());
    for (std::size_t p = 0; p < std::min(listed, pieces.size()); ++p) {
        const grid::VoxelPiece& piece = pieces.pieces()[p];
        std::printf("  %zu: %s voxels, %.6g mm^3, from (%.1f, %.1f, %.1f) to (%.1f, %.1f, %.1f) mm, %s\n", p + 1,
                    io::count_text(piece.voxels).c_str(), piece.volume_mm3, piece.min_mm.x(), piece.min_mm.y(),
                    piece.min_mm.z(), piece.max_mm.x(), piece.max_mm.y(), piece.max_mm.z(),
                    held[p] ? "held by a constraint" : "held by no constraint");
    }
    if (pieces.size() > listed)
        std::printf("  ... %zu more, of %s voxels or fewer each\n", pieces.size() - listed,
                    io::count_text(pieces.pieces()[listed].voxels).c_str());
    std::vector<std::size_t> loose;
    std::uint64_t loose_voxels = 0;
    for (std::size_t p = 0; p < pieces.size(); ++p)
        if (!held[p]) {
            loose.push_back(p + 1);
            loose_voxels += pieces.pieces()[p].voxels;
        }
    if (loose.empty()) return;
    std::string names;
    for (std::size_t k = 0; k < std::min<std::size_t>(loose.size(), 20); ++k)
        names += (k ? ", " : "") + std::to_string(loose[k]);
    if (loose.size() > 20) names += ", ...";
    log::warn("{}: {} of {} pieces ({} voxels) are held by no constraint: {} {}; they are {}; select pieces with "
              "object.select.components, min_voxels or seed_mm", path, loose.size(), pieces.size(), io::count_text(loose_voxels),
              loose.size() == 1 ? "piece" : "pieces", names, unheld_text(scene.object.unheld));
}

} // namespace

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
            if (m.rigid)
                std::printf("  label %d: %llu voxels, rigid, rho = %g kg/m^3\n", label, static_cast<unsigned long long>(n), m.density_kg_m3);
            else
                std::printf("  label %d: %llu voxels, E = %g Pa, nu = %g, rho = %g kg/m^3\n", label,
                            static_cast<unsigned long long>(n), m.youngs_modulus_pa, m.poisson_ratio, m.density_kg_m3);
        }
        list_pieces(scene, labels, *path);
        for (const std::string& line : sim::obstacle_overlaps(scene, sim::make_obstacles(scene), labels)) log::warn("{}", line);
        if (scene.object.auto_levels) {
            if (scene.object.step_budget_ms)
                std::printf("level: auto, the finest whose whole frames (tools, cuts, step) fit %g ms\n", *scene.object.step_budget_ms);
            else
                std::printf("level: auto, the coarsest within %g %% of the next finer level\n", 100 * scene.object.max_error.value_or(0.0));
        } else if (const auto& two = scene.object.mixed_levels) {
            // The elements per level where the run starts (the region then follows the tools).
            const grid::BranchedGrid grid = sim::build_scene_grid(scene, labels, two->coarse);
            const sim::RegionCells cells = sim::starting_region(scene, grid);
            const std::unique_ptr<grid::MixedLevels> mixed = sim::mixed_levels(grid, *two, cells);
            std::printf("levels %d within %g mm of the tools and %d elsewhere: where the run starts, %zu elements at level %d "
                        "(%zu cells of %d^3 voxels refined) and %zu at level %d, %zu border nodes tied\n",
                        two->fine, two->fine_radius_mm, two->coarse, mixed->fine_elements(), two->fine, cells.size(), 1 << two->coarse,
                        mixed->coarse_elements(), two->coarse, mixed->ties().size());
        } else {
            std::printf("level %d: %zu occupied cells of %d^3 voxels\n", level, grid::occupied_cells(labels, level).size(),
                        1 << level);
        }
        std::printf("solver: %s, dt %g s, CG tolerance %g, at most %d iterations\n",
                    io::solver_type_name(scene.solver.type).data(), scene.solver.dt_s,
                    scene.solver.cg_tolerance, scene.solver.cg_max_iterations);
        std::printf("constraints: %zu, obstacles: %zu, tools: %zu, script: %zu key frames", scene.constraints.size(),
                    scene.obstacles.size(), scene.tools.size(), scene.script.size());
        if (!scene.script.empty()) std::printf(" over %g s", scene.script.back().t_s - scene.script.front().t_s);
        std::printf("\noutput: %s\n", scene.output.dir.string().c_str());
    });
}

} // namespace vox::app
