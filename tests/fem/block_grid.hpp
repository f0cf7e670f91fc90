#pragma once
// The FEM tests' test object, a block phantom of one material (E = 1e5 Pa, nu = 0.3, 1000 kg/m^3),
// and its nodes on a plane.

#include "grid/branched_grid.hpp"
#include "grid/hex8.hpp"
#include "fem/hex_model.hpp"
#include "grid/phantom.hpp"

#include <cmath>
#include <vector>

namespace vox::test {

constexpr double k_e = 1e5, k_nu = 0.3, k_rho = 1000.0;

/// A block of `size_mm` in voxels of `voxel_mm` (first voxel centred at the origin), levels 1..`levels`.
inline grid::BranchedGrid block_grid(const Eigen::Vector3d& size_mm, int levels, double voxel_mm = 1.0)
{
    grid::PhantomSpec s = grid::default_phantom(grid::PhantomShape::block);
    s.size_mm = size_mm;
    s.voxel_mm = voxel_mm;
    return grid::BranchedGrid(grid::FineVoxels(grid::make_phantom(s), [](std::int32_t) { return 0; }),
                              {{grid::lame_from_young_poisson(k_e, k_nu), k_rho}}, levels);
}

/// Nodes whose rest coordinate `axis` equals `value` (m) to 1e-9.
inline std::vector<std::uint32_t> nodes_at(const fem::HexModel& m, int axis, double value)
{
    std::vector<std::uint32_t> out;
    for (std::uint32_t n = 0; n < m.node_count(); ++n)
        if (std::abs(m.rest_positions()[n][axis] - value) < 1e-9) out.push_back(n);
    return out;
}

} // namespace vox::test
