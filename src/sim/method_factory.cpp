#include "sim/method_factory.hpp"

#include "core/log.hpp"
#include "sim/dbg_method.hpp"
#include "sim/isxfem_method.hpp"

#include <algorithm>

namespace vox::sim {

OpenedMethod open_method(const io::Scene& scene, std::shared_ptr<const grid::LabelGrid> labels)
{
    OpenedMethod out;
    if (scene.solver.type == io::SolverType::isxfem) {
        out.method = std::make_unique<IsxfemMethod>(scene, std::move(labels), scene.object.levels);
        return out;
    }
    if (scene.object.auto_levels) { // every level is tried
        auto grid = std::make_unique<grid::BranchedGrid>(build_scene_grid(scene, *labels, 6));
        out.choice = choose_level(scene, *grid, labels);
        log::info("levels auto: {}", out.choice->reason);
        io::Scene chosen = scene;
        if (scene.solver.preconditioner == io::PreconditionerChoice::automatic)
            chosen.solver.preconditioner = out.choice->preconditioner; // measured fastest (budget); "auto" otherwise
        out.method = std::make_unique<DbgMethod>(chosen, std::move(labels), std::move(grid), out.choice->level);
        return out;
    }
    // Coarser levels than the simulated one serve only the multigrid preconditioner: every level
    // costs memory and time at each cut, so they are built only when the solver will use it.
    const int level = scene.object.levels, simulated = std::max(level, 1);
    if (scene.solver.type == io::SolverType::shape_matching) { // the clusters' levels above the simulated one
        auto grid = std::make_unique<grid::BranchedGrid>(
            build_scene_grid(scene, *labels, std::min(6, simulated + scene.solver.sm_cluster_levels)));
        out.method = std::make_unique<DbgMethod>(scene, std::move(labels), std::move(grid), level);
        return out;
    }
    auto grid = std::make_unique<grid::BranchedGrid>(build_scene_grid(scene, *labels, simulated));
    if (simulated < 6 && wants_multigrid(scene, *grid, level))
        grid = std::make_unique<grid::BranchedGrid>(build_scene_grid(scene, *labels, std::min(6, simulated + 3)));
    out.method = std::make_unique<DbgMethod>(scene, std::move(labels), std::move(grid), level);
    return out;
}

} // namespace vox::sim
