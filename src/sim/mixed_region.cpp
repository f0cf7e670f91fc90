#include "sim/mixed_region.hpp"

#include "sim/tool_policy.hpp"

#include <Eigen/Geometry>

namespace vox::sim {

std::unique_ptr<grid::MixedLevels> mixed_region(const io::Scene& scene, const grid::BranchedGrid& grid)
{
    const io::MixedLevelsSpec& spec = *scene.object.mixed_levels;
    std::vector<Eigen::AlignedBox3d> reach;
    std::vector<bool> placed(scene.tools.size(), false);
    for (const io::ScriptEntry& key : scene.script) {
        if (placed[key.tool_index]) continue;
        placed[key.tool_index] = true;
        const contact::ToolShape shape = make_tool_shape(scene.tools[key.tool_index]);
        reach.push_back(contact::PlacedShape{&shape, key.position_mm, key.orientation}.world_bounds(spec.fine_radius_mm));
    }
    if (reach.empty())
        throw scene.error("object.levels", "places its fine region around the tools where the run starts, and no tool has a key frame in \"script\"");
    const grid::FineVoxels& voxels = grid.voxels();
    const grid::Level& coarse = grid.level(spec.coarse);
    return std::make_unique<grid::MixedLevels>(grid, spec.fine, spec.coarse, [&](std::uint32_t e) {
        Eigen::AlignedBox3d cell;
        for (int c = 0; c < 8; ++c) cell.extend(voxels.world_mm(grid::BranchedGrid::cell_corner_index(coarse.elements[e].cell, spec.coarse, c)));
        for (const Eigen::AlignedBox3d& r : reach)
            if (r.intersects(cell)) return true;
        return false;
    });
}

} // namespace vox::sim
