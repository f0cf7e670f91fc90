#include "grid/coarse_cells.hpp"

#include <algorithm>

namespace vox::grid {

std::vector<Coord> occupied_cells(const LabelGrid& labels, int level)
{
    std::vector<Coord> cells;
    cells.reserve(labels.active_voxel_count() >> (3 * level));
    labels.for_each_active([&](const Coord& c, std::int32_t) {
        cells.emplace_back(c.x() >> level, c.y() >> level, c.z() >> level);
    });
    auto less = [](const Coord& a, const Coord& b) { return std::lexicographical_compare(a.begin(), a.end(), b.begin(), b.end()); };
    std::sort(cells.begin(), cells.end(), less);
    cells.erase(std::unique(cells.begin(), cells.end()), cells.end());
    return cells;
}

Eigen::Vector3d cell_corner_world(const LabelGrid& labels, const Coord& cell, int level, int corner)
{
    const double size = static_cast<double>(1 << level);
    const Eigen::Vector3d ijk((cell.x() + ((corner >> 0) & 1)) * size - 0.5, (cell.y() + ((corner >> 1) & 1)) * size - 0.5,
                              (cell.z() + ((corner >> 2) & 1)) * size - 0.5);
    return labels.index_to_world(ijk);
}

} // namespace vox::grid
