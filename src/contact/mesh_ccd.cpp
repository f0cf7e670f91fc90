#include "contact/mesh_ccd.hpp"

#include <algorithm>
#include <array>
#include <limits>
#include <set>
#include <tuple>

namespace vox::contact {

SweptBvh::SweptBvh(const MovingMesh& mesh)
{
    const std::size_t n = mesh.triangles.size();
    m_triangle_lo.resize(n);
    m_triangle_hi.resize(n);
    for (std::size_t t = 0; t < n; ++t) {
        Eigen::Vector3d lo = Eigen::Vector3d::Constant(std::numeric_limits<double>::infinity()), hi = -lo;
        for (int c = 0; c < 3; ++c)
            for (const auto* positions : {&mesh.start, &mesh.end}) {
                const Eigen::Vector3d& p = (*positions)[static_cast<std::size_t>(mesh.triangles[t][c])];
                lo = lo.cwiseMin(p);
                hi = hi.cwiseMax(p);
            }
        m_triangle_lo[t] = lo;
        m_triangle_hi[t] = hi;
    }
    m_order.resize(n);
    for (std::uint32_t t = 0; t < n; ++t) m_order[t] = t;
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
    const SweptBvh own(a); // the boxes of a's triangles
    using Points = std::array<Eigen::Vector3d, 4>;
    auto vertex_face = [&options](const MovingMesh& mv, int v, const MovingMesh& mf, const Eigen::Vector3i& f) {
        auto at = [](const std::vector<Eigen::Vector3d>& p, int i) { return p[static_cast<std::size_t>(i)]; };
        return vertex_face_ccd(Points{at(mv.start, v), at(mf.start, f[0]), at(mf.start, f[1]), at(mf.start, f[2])},
                               Points{at(mv.end, v), at(mf.end, f[0]), at(mf.end, f[1]), at(mf.end, f[2])}, options);
    };
    // (kind, first index, second index, first edge end, second edge end): each contact once.
    std::set<std::tuple<int, std::uint32_t, std::uint32_t, std::uint32_t, std::uint32_t>> found;
    for (std::uint32_t ta = 0; ta < a.triangles.size(); ++ta) {
        const Eigen::Vector3i& fa = a.triangles[ta];
        tree.query(own.lo(ta), own.hi(ta), [&](std::uint32_t tb) {
            const Eigen::Vector3i& fb = b.triangles[tb];
            for (int i = 0; i < 3; ++i) {
                if (vertex_face(a, fa[i], b, fb)) found.insert({MeshContact::vertex_a_face_b, static_cast<std::uint32_t>(fa[i]), tb, 0, 0});
                if (vertex_face(b, fb[i], a, fa)) found.insert({MeshContact::vertex_b_face_a, static_cast<std::uint32_t>(fb[i]), ta, 0, 0});
                for (int j = 0; j < 3; ++j) {
                    auto ea0 = static_cast<std::uint32_t>(fa[i]), ea1 = static_cast<std::uint32_t>(fa[(i + 1) % 3]);
                    auto eb0 = static_cast<std::uint32_t>(fb[j]), eb1 = static_cast<std::uint32_t>(fb[(j + 1) % 3]);
                    if (ea0 > ea1) std::swap(ea0, ea1); // an edge is shared by two triangles: test it once
                    if (eb0 > eb1) std::swap(eb0, eb1);
                    if (found.count({MeshContact::edge_edge, ea0, eb0, ea1, eb1})) continue;
                    if (edge_edge_ccd(Points{a.start[ea0], a.start[ea1], b.start[eb0], b.start[eb1]},
                                      Points{a.end[ea0], a.end[ea1], b.end[eb0], b.end[eb1]}, options))
                        found.insert({MeshContact::edge_edge, ea0, eb0, ea1, eb1});
                }
            }
        });
    }
    std::vector<MeshContact> out;
    for (const auto& [kind, x, y, x2, y2] : found) out.push_back({static_cast<MeshContact::Kind>(kind), x, y, x2, y2});
    return out;
}

} // namespace vox::contact
