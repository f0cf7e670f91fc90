#pragma once
// Surface snapshots for the contact and haptics tests, as the simulation publishes them.

#include "contact/surface_points.hpp"

#include <span>

namespace vox::test {

/// A flat wall z = 0 (the object below) sampled on a 1 mm grid of n x n points centred on the
/// origin, 1 mm^2 each, outward normal +z; with `triangles`, the grid's triangles and their tree.
inline contact::SurfacePoints flat_wall(int n = 41, bool triangles = false)
{
    contact::SurfacePoints s(static_cast<std::size_t>(n * n));
    const double half = 0.5 * (n - 1);
    for (int i = 0; i < n; ++i)
        for (int j = 0; j < n; ++j) {
            s.positions_mm[s.count] = Eigen::Vector3d(i - half, j - half, 0.0);
            s.normals[s.count] = Eigen::Vector3d::UnitZ();
            s.areas_mm2[s.count++] = 1.0;
        }
    if (triangles) {
        for (int i = 0; i + 1 < n; ++i)
            for (int j = 0; j + 1 < n; ++j) {
                const int a = i * n + j;
                s.triangles.emplace_back(a, a + n, a + n + 1);
                s.triangles.emplace_back(a, a + n + 1, a + 1);
            }
        const std::span<const Eigen::Vector3d> p(s.positions_mm.data(), s.count);
        s.triangle_tree.rebuild(p, p, s.triangles);
    s.edges = contact::surface_edges(s.triangles);
        s.edges = contact::surface_edges(s.triangles);
    }
    s.t_s = 0.0;
    return s;
}

/// A 20 x 20 mm square in z = 0 made of two triangles, sampled only at its four corners (100 mm^2
/// each): a surface whose points are far apart.
inline contact::SurfacePoints coarse_square()
{
    contact::SurfacePoints s(4);
    for (const Eigen::Vector3d& c : {Eigen::Vector3d(-10, -10, 0), Eigen::Vector3d(10, -10, 0), Eigen::Vector3d(10, 10, 0), Eigen::Vector3d(-10, 10, 0)}) {
        s.positions_mm[s.count] = c;
        s.normals[s.count] = Eigen::Vector3d::UnitZ();
        s.areas_mm2[s.count++] = 100.0;
    }
    s.triangles = {{0, 1, 2}, {0, 2, 3}};
    const std::span<const Eigen::Vector3d> p(s.positions_mm.data(), s.count);
    s.triangle_tree.rebuild(p, p, s.triangles);
    s.edges = contact::surface_edges(s.triangles);
    s.t_s = 0.0;
    return s;
}

} // namespace vox::test
