#pragma once
// Continuous collision between two triangle meshes moving linearly over a step (the tool and the
// object's surface): a bounding-volume hierarchy over each mesh's swept triangles (the box of each
// triangle at the start and end of the step) finds the pairs worth testing; every vertex-face pair
// (both ways) and edge-edge pair of overlapping triangles then goes through the conservative tests.

#include "contact/ccd.hpp"

#include <Eigen/Core>

#include <cstdint>
#include <span>
#include <vector>

namespace vox::contact {

struct MovingMesh {
    std::vector<Eigen::Vector3d> start, end; ///< vertex positions at t = 0 and t = 1
    std::vector<Eigen::Vector3i> triangles;
};

/// The box a triangle sweeps over the step (its corners at t = 0 and t = 1).
void swept_box(std::span<const Eigen::Vector3d> start, std::span<const Eigen::Vector3d> end, const Eigen::Vector3i& triangle,
               Eigen::Vector3d& lo, Eigen::Vector3d& hi) noexcept;

/// A box tree over a mesh's swept triangles (median split on the longest axis, leaves of up to 4).
class SweptBvh {
public:
    SweptBvh() = default;
    explicit SweptBvh(const MovingMesh& mesh) { rebuild(mesh.start, mesh.end, mesh.triangles); }
    /// Rebuilds the tree over `triangles` with corners at `start` and `end` (the same span for a
    /// mesh that does not move), reusing the storage it already has.
    void rebuild(std::span<const Eigen::Vector3d> start, std::span<const Eigen::Vector3d> end, std::span<const Eigen::Vector3i> triangles);
    /// Calls visit(triangle) for every triangle whose swept box overlaps [lo, hi].
    template <class F> void query(const Eigen::Vector3d& lo, const Eigen::Vector3d& hi, F&& visit) const;

private:
    struct Node {
        Eigen::Vector3d lo, hi;
        std::uint32_t first = 0, count = 0; ///< leaf: range in m_order; inner: count 0
        std::uint32_t left = 0, right = 0;
    };
    std::uint32_t build(std::uint32_t first, std::uint32_t count);

    std::vector<Eigen::Vector3d> m_triangle_lo, m_triangle_hi;
    std::vector<std::uint32_t> m_order;
    std::vector<Node> m_nodes;
};

struct MeshContact {
    enum Kind : std::uint8_t { vertex_a_face_b, vertex_b_face_a, edge_edge } kind;
    std::uint32_t a = 0, b = 0; ///< vertex or edge-start index in mesh a / face or edge in mesh b (see kind)
    std::uint32_t a2 = 0, b2 = 0; ///< edge ends for edge_edge
};

/// Every primitive pair of `a` and `b` that may touch during the step (conservative), each once.
[[nodiscard]] std::vector<MeshContact> mesh_ccd(const MovingMesh& a, const MovingMesh& b, const CcdOptions& options = {});

template <class F> void SweptBvh::query(const Eigen::Vector3d& lo, const Eigen::Vector3d& hi, F&& visit) const
{
    if (m_nodes.empty()) return;
    std::uint32_t stack[64];
    int top = 0;
    stack[top++] = 0;
    while (top > 0) {
        const Node& n = m_nodes[stack[--top]];
        if ((n.hi.array() < lo.array()).any() || (n.lo.array() > hi.array()).any()) continue;
        if (n.count) {
            for (std::uint32_t k = n.first; k < n.first + n.count; ++k) {
                const std::uint32_t t = m_order[k];
                if (!((m_triangle_hi[t].array() < lo.array()).any() || (m_triangle_lo[t].array() > hi.array()).any())) visit(t);
            }
        } else {
            stack[top++] = n.left;
            stack[top++] = n.right;
        }
    }
}

} // namespace vox::contact
