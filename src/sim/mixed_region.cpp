#include "sim/mixed_region.hpp"

#include "sim/tool_policy.hpp"

#include <algorithm>

namespace vox::sim {
namespace {

bool before(const grid::Coord& a, const grid::Coord& b) { return std::lexicographical_compare(a.data(), a.data() + 3, b.data(), b.data() + 3); }

void sort_unique(RegionCells& cells)
{
    std::sort(cells.begin(), cells.end(), before);
    cells.erase(std::unique(cells.begin(), cells.end()), cells.end());
}

bool meets(const Eigen::AlignedBox3d& box, std::span<const Eigen::AlignedBox3d> reach, double grown)
{
    return std::any_of(reach.begin(), reach.end(), [&](const Eigen::AlignedBox3d& r) {
        return Eigen::AlignedBox3d(r.min().array() - grown, r.max().array() + grown).intersects(box);
    });
}

} // namespace

RegionCells starting_region(const io::Scene& scene, const grid::BranchedGrid& grid)
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
    const grid::Level& coarse = grid.level(spec.coarse);
    RegionCells cells;
    for (const grid::Element& e : coarse.elements) {
        if (!e.alive) continue;
        Eigen::AlignedBox3d box;
        for (int c = 0; c < 8; ++c) box.extend(grid.voxels().world_mm(grid::BranchedGrid::cell_corner_index(e.cell, spec.coarse, c)));
        if (meets(box, reach, 0.0)) cells.push_back(e.cell);
    }
    sort_unique(cells);
    return cells;
}

RegionCells followed_region(const grid::BranchedGrid& grid, const fem::HexModel& model, const std::vector<Eigen::Vector3d>& positions_m,
                            std::span<const Eigen::AlignedBox3d> reach_mm, const RegionCells& current)
{
    const int coarse = model.coarse_level();
    const grid::Level& level = grid.level(coarse);
    // Each coarse element's material where it is now: the box of its model element's nodes, or
    // of its fine descendants' nodes.
    std::vector<Eigen::AlignedBox3d> box(level.elements.size());
    for (const fem::HexElement& el : model.elements()) {
        const std::uint32_t e = el.level == coarse ? el.grid_element : grid::ancestor(grid, el.level, el.grid_element, coarse);
        for (std::uint32_t n : el.dof_node) box[e].extend(positions_m[n] * 1e3);
    }
    const double half_cell_mm = 0.5 * static_cast<double>(1 << coarse) * 1e3 * grid.voxels().voxel_size_m().maxCoeff();
    RegionCells cells;
    for (std::uint32_t e = 0; e < level.elements.size(); ++e) {
        if (box[e].isEmpty()) continue;
        const grid::Coord& cell = level.elements[e].cell;
        const bool fine_now = std::binary_search(current.begin(), current.end(), cell, before);
        if (meets(box[e], reach_mm, fine_now ? half_cell_mm : 0.0)) cells.push_back(cell);
    }
    sort_unique(cells);
    return cells;
}

std::unique_ptr<grid::MixedLevels> mixed_levels(const grid::BranchedGrid& grid, const io::MixedLevelsSpec& spec, const RegionCells& cells)
{
    const grid::Level& coarse = grid.level(spec.coarse);
    return std::make_unique<grid::MixedLevels>(grid, spec.fine, spec.coarse, [&](std::uint32_t e) {
        return std::binary_search(cells.begin(), cells.end(), coarse.elements[e].cell, before);
    });
}

} // namespace vox::sim
