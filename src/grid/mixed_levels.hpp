#pragma once
// Two levels of the branched grid in one model: the elements of a fine level in a region, those of
// a coarse level elsewhere. A coarse element whose cell is refined is replaced by its descendants
// at the fine level (the fine elements whose voxels it holds), so mass and stiffness stay the
// grid's exact condensation at both levels.
//
// The two meet without cracks: a fine node on the region's border that the fine level shares with
// fine elements outside the region (that is, whose material connects across the border) follows
// the coarse element holding those outside fine elements: its displacement is that element's
// trilinear field at the node. Where a coarse cell holds superimposed elements (an arm of a U on
// each side of a gap), a border node thus follows the arm whose material it connects to, and a
// node that connects to no outside material stays free. A coarse element's trace on a face is
// bilinear, and a bilinear function restricted to a fine face is the bilinear interpolation of its
// values at that face's corners: the field is continuous across the border.

#include "grid/branched_grid.hpp"

#include <Eigen/Core>

#include <array>
#include <cstdint>
#include <functional>
#include <vector>

namespace vox::grid {

class MixedLevels {
public:
    /// One element of the mixed model: a grid element of `level` (fine or coarse).
    struct Element {
        int level = 0;
        std::uint32_t element = 0;
        std::array<std::uint32_t, 8> nodes{}; ///< mixed node per corner (bits +x, +y, +z)
    };
    /// A fine node on the border: its displacement is sum_c weight[c] * displacement(masters[c]),
    /// the trilinear field of the coarse element it follows (masters are that element's corners).
    struct Tie {
        std::uint32_t node = 0;
        std::uint32_t coarse_element = 0; ///< grid element id at the coarse level
        std::array<std::uint32_t, 8> masters{};
        std::array<double, 8> weights{};
    };

    /// `refine(e)` says whether alive element e of level `coarse` is replaced by its descendants at
    /// level `fine` (1 <= fine < coarse <= grid.max_level()).
    MixedLevels(const BranchedGrid& grid, int fine, int coarse, const std::function<bool(std::uint32_t)>& refine);

    [[nodiscard]] int fine() const { return m_fine; }
    [[nodiscard]] int coarse() const { return m_coarse; }
    [[nodiscard]] const std::vector<Element>& elements() const { return m_elements; }
    [[nodiscard]] std::size_t node_count() const { return m_node_level.size(); }
    /// Level (fine or coarse) and grid node id of each mixed node.
    [[nodiscard]] int node_level(std::uint32_t n) const { return m_node_level[n]; }
    [[nodiscard]] std::uint32_t grid_node(std::uint32_t n) const { return m_grid_node[n]; }
    /// Rest position of each mixed node, world mm.
    [[nodiscard]] const std::vector<Eigen::Vector3d>& rest_positions_mm() const { return m_rest_mm; }
    [[nodiscard]] const std::vector<Tie>& ties() const { return m_ties; }
    /// Elements of the fine and of the coarse level in the model.
    [[nodiscard]] std::size_t fine_elements() const { return m_fine_elements; }
    [[nodiscard]] std::size_t coarse_elements() const { return m_elements.size() - m_fine_elements; }

private:
    int m_fine, m_coarse;
    std::vector<Element> m_elements; ///< fine ones first
    std::size_t m_fine_elements = 0;
    std::vector<int> m_node_level;
    std::vector<std::uint32_t> m_grid_node;
    std::vector<Eigen::Vector3d> m_rest_mm;
    std::vector<Tie> m_ties;
};

/// The element of level `to` holding element e of level `from` (from <= to; level 0: voxel slot).
[[nodiscard]] std::uint32_t ancestor(const BranchedGrid& grid, int from, std::uint32_t e, int to);

} // namespace vox::grid
