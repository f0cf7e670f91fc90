#include "contact/surface_points.hpp"

#include <type_traits>

namespace vox::contact {

void SurfacePoints::index()
{
    grid = PointGrid{};
    slack_pose = PlacedShape{}; // measured anew for these positions, if at all
    patch.count = patch.free = 0; // built anew around the contact, if at all (contact/contact_patch.hpp)
    replaced.clear();
    if (count == 0) {
        triangle_tree.rebuild({}, {}, triangles);
        edges.clear();
        return;
    }
    Eigen::AlignedBox3d box;
    box.setEmpty();
    for (std::size_t i = 0; i < count; ++i) box.extend(positions_mm[i]);
    // Cells of 1 mm (a knife's reach covers a few hundred of them), fewer and larger on a snapshot
    // so large that there would be more than 2^18.
    const Eigen::Vector3d extent = box.sizes().cwiseMax(1e-6);
    grid.cell_mm = std::max(1.0, std::cbrt(extent.prod() / 262144.0));
    grid.origin = box.min();
    for (int a = 0; a < 3; ++a) grid.cells[a] = static_cast<int>(extent[a] / grid.cell_mm) + 1;
    const std::size_t cells = static_cast<std::size_t>(grid.cells.prod());
    auto cell_of = [&](const Eigen::Vector3d& p) {
        Eigen::Vector3i c;
        for (int a = 0; a < 3; ++a) c[a] = std::clamp(static_cast<int>((p[a] - grid.origin[a]) / grid.cell_mm), 0, grid.cells[a] - 1);
        return static_cast<std::size_t>(c.x() + grid.cells.x() * (c.y() + static_cast<std::size_t>(grid.cells.y()) * c.z()));
    };
    // The points sorted by their cell (a counting sort) and stored in that order: a tick reads the
    // points near the tool from a few runs of memory, not scattered over the snapshot (a knife
    // deep in its cut touches hundreds; cache misses were a quarter of such a tick).
    std::vector<std::size_t> point_cell(count);
    grid.point_start.assign(cells + 1, 0);
    for (std::size_t i = 0; i < count; ++i) ++grid.point_start[(point_cell[i] = cell_of(positions_mm[i])) + 1];
    for (std::size_t c = 0; c < cells; ++c) grid.point_start[c + 1] += grid.point_start[c];
    std::vector<std::uint32_t> fill(grid.point_start.begin(), grid.point_start.end() - 1);
    std::vector<int> moved_to(count);
    for (std::size_t i = 0; i < count; ++i) moved_to[i] = static_cast<int>(fill[point_cell[i]]++);
    const auto reorder = [&](auto& values) {
        if (values.size() < count) return;
        std::remove_reference_t<decltype(values)> sorted(count); // the points in use, not the whole capacity
        for (std::size_t i = 0; i < count; ++i) sorted[static_cast<std::size_t>(moved_to[i])] = values[i];
        std::copy_n(sorted.begin(), count, values.begin());
    };
    reorder(positions_mm);
    reorder(normals);
    reorder(areas_mm2);
    reorder(stiffness_n_per_mm);
    for (Eigen::Vector3i& t : triangles)
        for (int c = 0; c < 3; ++c) t[c] = moved_to[static_cast<std::size_t>(t[c])];
    const std::span<const Eigen::Vector3d> positions(positions_mm.data(), count);
    triangle_tree.rebuild(positions, positions, triangles);
    edges = surface_edges(triangles);
    // Each edge's ball (middle and half length) once; the longest edge bounds a query's growth.
    std::vector<PointGrid::Edge> balls(edges.size());
    std::vector<std::size_t> edge_cell(edges.size());
    grid.edge_start.assign(cells + 1, 0);
    for (std::size_t k = 0; k < edges.size(); ++k) {
        const Eigen::Vector3d &a = positions_mm[static_cast<std::size_t>(edges[k][0])], &b = positions_mm[static_cast<std::size_t>(edges[k][1])];
        const double half = 0.5 * (b - a).norm();
        balls[k] = {edges[k], (0.5 * (a + b)).cast<float>(), static_cast<float>(half)};
        grid.longest_edge_mm = std::max(grid.longest_edge_mm, 2.0 * half);
        ++grid.edge_start[(edge_cell[k] = cell_of(0.5 * (a + b))) + 1];
    }
    for (std::size_t c = 0; c < cells; ++c) grid.edge_start[c + 1] += grid.edge_start[c];
    grid.edges.resize(edges.size());
    fill.assign(grid.edge_start.begin(), grid.edge_start.end() - 1);
    for (std::size_t k = 0; k < edges.size(); ++k) grid.edges[fill[edge_cell[k]]++] = balls[k];
}

} // namespace vox::contact
