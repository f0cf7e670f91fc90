#include "contact/mesh_ccd.hpp"

#include <algorithm>
#include <array>
#include <limits>
#include <set>
#include <tuple>

namespace vox::contact {

void swept_box(std::span<const Eigen::Vector3d> start, std::span<const Eigen::Vector3d> end, const Eigen::Vector3i& triangle,
               Eigen::Vector3d& lo, Eigen::Vector3d& hi) noexcept
{
    lo = Eigen::Vector3d::Constant(std::numeric_limits<double>::infinity());
    hi = -lo;
    for (int c = 0; c < 3; ++c) {
        const auto v = static_cast<std::size_t>(triangle[c]);
        lo = lo.cwiseMin(start[v]).cwiseMin(end[v]);
        hi = hi.cwiseMax(start[v]).cwiseMax(end[v]);
    }
}

void SweptBvh::rebuild(std::span<const Eigen::Vector3d> start, std::span<const Eigen::Vector3d> end,
                       std::span<const Eigen::Vector3i> triangles)
{
    const std::size_t n = triangles.size();
    m_triangle_lo.resize(n);
    m_triangle_hi.resize(n);
    for (std::size_t t = 0; t < n; ++t) swept_box(start, end, triangles[t], m_triangle_lo[t], m_triangle_hi[t]);
    m_order.resize(n);
    for (std::uint32_t t = 0; t < n; ++t) m_order[t] = t;
    m_nodes.clear();
    if (n) {
        m_nodes.reserve(2 * n);
        build(0, static_cast<std::uint32_t>(n));
    }
}

std::uint32_t SweptBvh::build(std::uint32_t first, std::uint32_t count)
{
    const auto index = static_cast<std::uint32_t>(m_nodes.size());
    m_nodes.emplace_back();
    Eigen::Vector3d lo = Eigen::Vector3d::Constant(std::numeric_limits<double>::infinity()), hi = -lo;
    for (std::uint32_t k = first; k < first + count; ++k) {
        lo = lo.cwiseMin(m_triangle_lo[m_order[k]]);
        hi = hi.cwiseMax(m_triangle_hi[m_order[k]]);
    }
    m_nodes[index].lo = lo;
    m_nodes[index].hi = hi;
    if (count <= 4) {
        m_nodes[index].first = first;
        m_nodes[index].count = count;
        return index;
    }
    int axis = 0;
    (hi - lo).maxCoeff(&axis);
    const auto middle = m_order.begin() + first + count / 2;
    std::nth_element(m_order.begin() + first, middle, m_order.begin() + first + count, [&](std::uint32_t x, std::uint32_t y) {
        return m_triangle_lo[x][axis] + m_triangle_hi[x][axis] < m_triangle_lo[y][axis] + m_triangle_hi[y][axis];
    });
    const std::uint32_t left = build(first, count / 2);
    const std::uint32_t right = build(first + count / 2, count - count / 2);
    m_nodes[index].left = left;
    m_nodes[index].right = right;
    return index;
}

std::vector<MeshContact> mesh_ccd(const MovingMesh& a, const MovingMesh& b, const CcdOptions& options)
{
    const SweptBvh tree(b);
    using Points = std::array<Eigen::Vector3d, 4>;
    auto at = [](const std::vector<Eigen::Vector3d>& p, std::uint32_t i) { return p[i]; };
    // A vertex sits in about six triangles and an edge in two, so the same primitive pair comes up
    // from several triangle pairs: each is tested once. Key: (kind, index, index, end, end).
    using Key = std::tuple<int, std::uint32_t, std::uint32_t, std::uint32_t, std::uint32_t>;
    std::set<Key> tested, found;
    auto test = [&](const Key& key, auto&& collides) {
        if (tested.insert(key).second && collides()) found.insert(key);
    };
    auto vertex_face = [&](const MovingMesh& mv, std::uint32_t v, const MovingMesh& mf, const Eigen::Vector3i& f) {
        auto c = [&f](int k) { return static_cast<std::uint32_t>(f[k]); };
        return vertex_face_ccd(Points{at(mv.start, v), at(mf.start, c(0)), at(mf.start, c(1)), at(mf.start, c(2))},
                               Points{at(mv.end, v), at(mf.end, c(0)), at(mf.end, c(1)), at(mf.end, c(2))}, options);
    };
    for (std::uint32_t ta = 0; ta < a.triangles.size(); ++ta) {
        const Eigen::Vector3i& fa = a.triangles[ta];
        Eigen::Vector3d lo, hi;
        swept_box(a.start, a.end, fa, lo, hi);
        tree.query(lo, hi, [&](std::uint32_t tb) {
            const Eigen::Vector3i& fb = b.triangles[tb];
            for (int i = 0; i < 3; ++i) {
                const auto va = static_cast<std::uint32_t>(fa[i]), vb = static_cast<std::uint32_t>(fb[i]);
                test({MeshContact::vertex_a_face_b, va, tb, 0, 0}, [&] { return vertex_face(a, va, b, fb); });
                test({MeshContact::vertex_b_face_a, vb, ta, 0, 0}, [&] { return vertex_face(b, vb, a, fa); });
                for (int j = 0; j < 3; ++j) {
                    auto ea0 = static_cast<std::uint32_t>(fa[i]), ea1 = static_cast<std::uint32_t>(fa[(i + 1) % 3]);
                    auto eb0 = static_cast<std::uint32_t>(fb[j]), eb1 = static_cast<std::uint32_t>(fb[(j + 1) % 3]);
                    if (ea0 > ea1) std::swap(ea0, ea1);
                    if (eb0 > eb1) std::swap(eb0, eb1);
                    test({MeshContact::edge_edge, ea0, eb0, ea1, eb1}, [&] {
                        return edge_edge_ccd(Points{a.start[ea0], a.start[ea1], b.start[eb0], b.start[eb1]},
                                             Points{a.end[ea0], a.end[ea1], b.end[eb0], b.end[eb1]}, options);
                    });
                }
            }
        });
    }
    std::vector<MeshContact> out;
    for (const auto& [kind, x, y, x2, y2] : found) out.push_back({static_cast<MeshContact::Kind>(kind), x, y, x2, y2});
    return out;
}

} // namespace vox::contact
