#include "grid/voxel_pieces.hpp"

#include "core/union_find.hpp"

#include <Eigen/LU>

#include <algorithm>
#include <cmath>
#include <limits>
#include <numeric>

namespace vox::grid {
namespace {

bool zyx_less(const Coord& a, const Coord& b)
{
    if (a.z() != b.z()) return a.z() < b.z();
    if (a.y() != b.y()) return a.y() < b.y();
    return a.x() < b.x();
}

} // namespace

VoxelPieces::VoxelPieces(const LabelGrid& labels)
{
    m_coords.reserve(labels.active_voxel_count());
    labels.for_each_active([&](const Coord& c, std::int32_t) { m_coords.push_back(c); });
    std::sort(m_coords.begin(), m_coords.end(), zyx_less);
    const auto n = static_cast<std::uint32_t>(m_coords.size());
    UnionFind sets(n);
    for (std::uint32_t v = 0; v < n; ++v) {
        const Coord& c = m_coords[v];
        // -x: the previous voxel when adjacent; -y and -z by search (all earlier in the order).
        if (v > 0 && m_coords[v - 1] == Coord(c.x() - 1, c.y(), c.z())) sets.unite(v - 1, v);
        for (const Coord& below : {Coord(c.x(), c.y() - 1, c.z()), Coord(c.x(), c.y(), c.z() - 1)}) {
            const auto it = std::lower_bound(m_coords.begin(), m_coords.begin() + v, below, zyx_less);
            if (it != m_coords.begin() + v && *it == below)
                sets.unite(static_cast<std::uint32_t>(it - m_coords.begin()), v);
        }
    }
    // Roots are the smallest index of their set, so root order is first-voxel order.
    std::vector<std::uint32_t> root_piece(n, none);
    std::vector<std::uint32_t> roots;
    std::vector<std::uint64_t> counts;
    m_piece.resize(n);
    for (std::uint32_t v = 0; v < n; ++v) {
        const std::uint32_t r = sets.find(v);
        if (root_piece[r] == none) {
            root_piece[r] = static_cast<std::uint32_t>(roots.size());
            roots.push_back(r);
            counts.push_back(0);
        }
        m_piece[v] = root_piece[r];
        ++counts[m_piece[v]];
    }
    std::vector<std::uint32_t> order(roots.size());
    std::iota(order.begin(), order.end(), 0u);
    std::stable_sort(order.begin(), order.end(), [&](std::uint32_t a, std::uint32_t b) { return counts[a] > counts[b]; });
    std::vector<std::uint32_t> rank(order.size());
    for (std::uint32_t i = 0; i < order.size(); ++i) rank[order[i]] = i;

    const Eigen::Matrix3d linear = labels.index_to_world().topLeftCorner<3, 3>();
    const double voxel_mm3 = std::abs(linear.determinant());
    m_pieces.assign(order.size(), VoxelPiece{});
    for (auto& p : m_pieces) {
        p.bounds.min = Coord(std::numeric_limits<std::int32_t>::max(), std::numeric_limits<std::int32_t>::max(),
                             std::numeric_limits<std::int32_t>::max());
        p.bounds.max = Coord(std::numeric_limits<std::int32_t>::min(), std::numeric_limits<std::int32_t>::min(),
                             std::numeric_limits<std::int32_t>::min());
    }
    for (std::uint32_t v = 0; v < n; ++v) {
        m_piece[v] = rank[m_piece[v]];
        VoxelPiece& p = m_pieces[m_piece[v]];
        ++p.voxels;
        p.bounds.min = p.bounds.min.cwiseMin(m_coords[v]);
        p.bounds.max = p.bounds.max.cwiseMax(m_coords[v]);
    }
    for (VoxelPiece& p : m_pieces) {
        p.volume_mm3 = static_cast<double>(p.voxels) * voxel_mm3;
        // The world box of the index box's eight outer corners (the voxels' extents).
        p.min_mm = Eigen::Vector3d::Constant(std::numeric_limits<double>::max());
        p.max_mm = Eigen::Vector3d::Constant(std::numeric_limits<double>::lowest());
        for (int corner = 0; corner < 8; ++corner) {
            const Eigen::Vector3d ijk((corner & 1) ? p.bounds.max.x() + 0.5 : p.bounds.min.x() - 0.5,
                                      (corner & 2) ? p.bounds.max.y() + 0.5 : p.bounds.min.y() - 0.5,
                                      (corner & 4) ? p.bounds.max.z() + 0.5 : p.bounds.min.z() - 0.5);
            const Eigen::Vector3d w = labels.index_to_world(ijk);
            p.min_mm = p.min_mm.cwiseMin(w);
            p.max_mm = p.max_mm.cwiseMax(w);
        }
    }
}

std::uint32_t VoxelPieces::piece_at(const Coord& ijk) const
{
    const auto it = std::lower_bound(m_coords.begin(), m_coords.end(), ijk, zyx_less);
    return it != m_coords.end() && *it == ijk ? m_piece[static_cast<std::size_t>(it - m_coords.begin())] : none;
}

LabelGrid keep_pieces(const LabelGrid& labels, const VoxelPieces& pieces, const std::vector<bool>& keep)
{
    LabelGrid out(labels.index_to_world());
    out.copy_metadata(labels);
    const auto& coords = pieces.voxels();
    const auto& which = pieces.voxel_pieces();
    for (std::size_t v = 0; v < coords.size(); ++v)
        if (keep[which[v]]) out.set(coords[v], labels.get(coords[v]));
    return out;
}

} // namespace vox::grid
