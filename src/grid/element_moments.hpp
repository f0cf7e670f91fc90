#pragma once
// An exact representation of what a coarse element holds: for each material, the 27 integer
// moments of its fine voxels, 216 * integral of u^a v^b w^c over the voxels (a, b, c in 0..2;
// u, v, w the cell-local coordinates in voxel units, voxel (i, j, k) spanning [i, i+1] x ...).
// A trilinear element's stiffness and consistent mass are integrals of polynomials of degree at
// most 2 per axis, hence linear in these moments: adding or removing voxels is integer
// arithmetic that never drifts, and the matrices follow in O(1) (MomentMatrices).
// The factor 216 = 6^3 makes every moment an integer; cells up to 64 voxels per axis fit in 64 bits.

#include "core/eigen_types.hpp"
#include "grid/elastic_material.hpp"

#include <array>
#include <cstdint>
#include <span>
#include <vector>

namespace vox::grid {

/// 27 scaled moments, index a + 3 b + 9 c.
using Moments = std::array<std::int64_t, 27>;

/// moments += sign * moments of the voxel at cell-local index (i, j, k).
void add_voxel_moments(Moments& moments, const Eigen::Vector3i& local, int sign = 1);
/// moments += sign * moments of the full box of `size` voxels per axis at local offset `origin`.
void add_box_moments(Moments& moments, const Eigen::Vector3i& origin, int size, int sign = 1);

/// Moments per material of one element, sorted by material; materials with no voxel left are removed.
struct MaterialMoments {
    std::int32_t material = 0;
    std::uint32_t voxels = 0;
    Moments moments{};
};
using ElementContent = std::vector<MaterialMoments>;

/// Adds (sign = +1) or removes (-1) one voxel of `material` at `local` to/from `content`.
void update_content(ElementContent& content, std::int32_t material, const Eigen::Vector3i& local, int sign);

/// The linear maps from moments to matrices for cells of 2^level voxels per axis and fine voxel
/// edges `voxel_size_m`.
class MomentMatrices {
public:
    MomentMatrices(int level, const Eigen::Vector3d& voxel_size_m);

    /// Stiffness (N/m) and scalar consistent mass (kg) of an element holding `content`.
    [[nodiscard]] Matrix24d stiffness(const ElementContent& content, std::span<const ElasticMaterial> materials) const;
    [[nodiscard]] Matrix8d mass(const ElementContent& content, std::span<const ElasticMaterial> materials) const;

private:
    /// For corner pair (c, d) and derivative axes (i, j): the 27 coefficients of
    /// integral dN_c/dx_i dN_d/dx_j dx over moments; and for the mass, of integral N_c N_d dx.
    std::array<std::array<std::array<double, 27>, 9>, 64> m_gradient{};
    std::array<std::array<double, 27>, 64> m_shape{};
};

} // namespace vox::grid
