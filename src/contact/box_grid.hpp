#pragma once
// Boxes sorted into the cells of a uniform grid that they meet: the broad phase of contact between
// parts of a surface (triangles near a vertex, elements near each other). The boxes are counted
// into a dense array of the cells they span together, not sorted by cell key: a comparison sort
// of the entries took a third of a frame's broad phase on the liver. When the boxes spread so far
// that the array would be much larger than their count (a piece fallen a metre away), cells are
// merged, 2^k to a side, until it is not.

#include <Eigen/Geometry>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <vector>

namespace vox::contact {

class BoxGrid {
public:
    /// `cell`: the cells' edge, in the boxes' units (about the size of a box: each meets a few).
    BoxGrid(std::vector<Eigen::AlignedBox3d> boxes, double cell) : m_boxes(std::move(boxes)), m_cell(cell)
    {
        if (m_boxes.empty()) return;
        m_low.resize(m_boxes.size());
        m_high.resize(m_boxes.size());
        m_lowest = Eigen::Array3i::Constant(std::numeric_limits<int>::max());
        Eigen::Array3i highest = -m_lowest;
        for (std::size_t i = 0; i < m_boxes.size(); ++i) {
            m_low[i] = unmerged(m_boxes[i].min());
            m_high[i] = unmerged(m_boxes[i].max());
            m_lowest = m_lowest.min(m_low[i]);
            highest = highest.max(m_high[i]);
        }
        const Eigen::Array<std::int64_t, 3, 1> span = (highest - m_lowest + 1).cast<std::int64_t>();
        const auto wanted = static_cast<std::int64_t>(std::max<std::size_t>(64, 16 * m_boxes.size()));
        auto merged = [&](int by) { return span.unaryExpr([by](std::int64_t n) { return ((n - 1) >> by) + 1; }).eval(); };
        while (merged(m_merge).prod() > wanted) ++m_merge;
        m_dims = merged(m_merge).cast<int>();
        for (std::size_t i = 0; i < m_boxes.size(); ++i) {
            m_low[i] = shrink(m_low[i]);
            m_high[i] = shrink(m_high[i]);
        }
        m_start.assign(static_cast<std::size_t>(m_dims.prod()) + 1, 0);
        for (std::size_t i = 0; i < m_boxes.size(); ++i) for_cells(m_low[i], m_high[i], [&](std::size_t c) { ++m_start[c + 1]; });
        for (std::size_t c = 1; c < m_start.size(); ++c) m_start[c] += m_start[c - 1];
        m_items.resize(m_start.back());
        std::vector<std::uint32_t> fill(m_start.begin(), m_start.end() - 1);
        for (std::size_t i = 0; i < m_boxes.size(); ++i)
            for_cells(m_low[i], m_high[i], [&](std::size_t c) { m_items[fill[c]++] = static_cast<std::uint32_t>(i); });
    }

    [[nodiscard]] const std::vector<Eigen::AlignedBox3d>& boxes() const { return m_boxes; }

    /// Calls f(i) for every box listed in a cell that `box` meets (a box may come more than once).
    template <class F>
    void near(const Eigen::AlignedBox3d& box, F&& f) const
    {
        if (m_boxes.empty()) return;
        const Eigen::Array3i lo = shrink(unmerged(box.min()).max(m_lowest)).max(0), hi = shrink(unmerged(box.max()).max(m_lowest)).min(m_dims - 1);
        if ((unmerged(box.max()) < m_lowest).any() || (lo > hi).any()) return;
        for_cells(lo, hi, [&](std::size_t c) {
            for (std::uint32_t k = m_start[c]; k < m_start[c + 1]; ++k) f(m_items[k]);
        });
    }

    /// Calls f(i, j), i < j, once for every two boxes that overlap: in the one cell they share that
    /// holds their overlap's low corner (neighbours share most of their cells).
    template <class F>
    void overlapping_pairs(F&& f) const
    {
        for (std::size_t c = 0; c + 1 < m_start.size(); ++c)
            for (std::uint32_t a = m_start[c]; a < m_start[c + 1]; ++a)
                for (std::uint32_t b = a + 1; b < m_start[c + 1]; ++b) {
                    const std::uint32_t i = std::min(m_items[a], m_items[b]), j = std::max(m_items[a], m_items[b]);
                    const Eigen::Array3i corner = m_low[i].max(m_low[j]);
                    if (slot(corner.x(), corner.y(), corner.z()) == c && m_boxes[i].intersects(m_boxes[j])) f(i, j);
                }
    }

private:
    /// The cell of a point, before merging (clamped, so that a point a kilometre away still counts).
    [[nodiscard]] Eigen::Array3i unmerged(const Eigen::Vector3d& at) const
    {
        return (at.array() / m_cell).floor().max(-1e6).min(1e6).cast<int>();
    }
    [[nodiscard]] Eigen::Array3i shrink(const Eigen::Array3i& c) const
    {
        return (c - m_lowest).unaryExpr([this](int n) { return n >> m_merge; });
    }
    [[nodiscard]] std::size_t slot(int x, int y, int z) const
    {
        return static_cast<std::size_t>((static_cast<std::int64_t>(z) * m_dims.y() + y) * m_dims.x() + x);
    }
    template <class F>
    void for_cells(const Eigen::Array3i& lo, const Eigen::Array3i& hi, F&& f) const
    {
        for (int z = lo.z(); z <= hi.z(); ++z)
            for (int y = lo.y(); y <= hi.y(); ++y)
                for (int x = lo.x(); x <= hi.x(); ++x) f(slot(x, y, z));
    }

    std::vector<Eigen::AlignedBox3d> m_boxes;
    double m_cell;
    std::vector<Eigen::Array3i> m_low, m_high; ///< per box, its cells (merged, from m_lowest)
    Eigen::Array3i m_lowest = Eigen::Array3i::Zero(), m_dims = Eigen::Array3i::Zero();
    int m_merge = 0;
    std::vector<std::uint32_t> m_start, m_items; ///< per cell, its range of m_items
};

} // namespace vox::contact
