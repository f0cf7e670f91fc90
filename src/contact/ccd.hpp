#pragma once
// Continuous collision detection of two primitives moving linearly over a time step t in [0, 1]:
// vertex-face (a point against a triangle) and edge-edge. Conservative: a query that has a
// contact is never answered false; a query answered true may have none (a false positive).
//
// The contact conditions, written on relative positions that are linear in t: the four points are
// coplanar (the cubic coplanarity equation, Provot 1997; Tang et al. 2010) and, at the same time,
// the point lies inside the triangle / the two segments cross (sign conditions of degree 4 in t).
// Instead of solving the cubic in floating point, which misses roots at tangencies and on
// degenerate (always coplanar) motions, every condition is bounded over a time interval by
// interval arithmetic with outward widening (error bounds on each operation, and on the inputs'
// own rounding): an interval is discarded only when some condition provably fails throughout it,
// else halved, down to a minimum width at which the query is reported as a contact.

#include <Eigen/Core>

#include <array>

namespace vox::contact {

struct CcdOptions {
    int max_depth = 24;        ///< halvings of [0, 1] before a surviving interval counts as contact
    double input_ulps = 1.0;   ///< each input coordinate is taken as x (1 +- input_ulps eps)
};

/// `at0` = {vertex, face corner 0, 1, 2} at t = 0, `at1` the same at t = 1.
[[nodiscard]] bool vertex_face_ccd(const std::array<Eigen::Vector3d, 4>& at0, const std::array<Eigen::Vector3d, 4>& at1,
                                   const CcdOptions& options = {});
/// `at0` = {edge a end 0, a end 1, edge b end 0, b end 1} at t = 0, `at1` at t = 1.
[[nodiscard]] bool edge_edge_ccd(const std::array<Eigen::Vector3d, 4>& at0, const std::array<Eigen::Vector3d, 4>& at1,
                                 const CcdOptions& options = {});

/// The time of first possible contact in [0, 1] of the same queries: a lower bound on the true
/// one (never later; within 2^-max_depth when the contact is real and the primitives are not
/// degenerate), infinity when the query has none. For degenerate pairs (parallel edges, a
/// sliver face) the bounds may not rule out the time the two boxes first overlap, which is then
/// what is returned: conservative, possibly early. Times at or after `before` are not searched
/// (infinity is returned instead): a caller after the earliest contact of many pairs passes the
/// earliest so far. Never allocates or throws (the haptic loop calls them).
[[nodiscard]] double vertex_face_toi(const std::array<Eigen::Vector3d, 4>& at0, const std::array<Eigen::Vector3d, 4>& at1,
                                     const CcdOptions& options = {}, double before = 2.0) noexcept;
[[nodiscard]] double edge_edge_toi(const std::array<Eigen::Vector3d, 4>& at0, const std::array<Eigen::Vector3d, 4>& at1,
                                   const CcdOptions& options = {}, double before = 2.0) noexcept;

/// The same two queries when one side translates by `move` over the step and the other stays (the
/// haptic proxy's step against a snapshot). The coplanarity condition is then linear in t: its
/// root is bounded directly, and the inside conditions checked over that bound, instead of halving
/// [0, 1] towards it; as conservative as the general queries, and tighter than they are at any
/// depth. Where the motion keeps the four points coplanar, or the root is not bounded to within
/// 2^-max_depth (a move almost parallel to the face or to both edges), the general query answers.
/// Vertex `vertex` against the still face `face`; edge `edge` against the still edge `other`.
[[nodiscard]] double translating_vertex_face_toi(const Eigen::Vector3d& vertex, const Eigen::Vector3d& move,
                                                 const std::array<Eigen::Vector3d, 3>& face, const CcdOptions& options = {},
                                                 double before = 2.0) noexcept;
[[nodiscard]] double translating_edge_edge_toi(const std::array<Eigen::Vector3d, 2>& edge, const Eigen::Vector3d& move,
                                               const std::array<Eigen::Vector3d, 2>& other, const CcdOptions& options = {},
                                               double before = 2.0) noexcept;

} // namespace vox::contact
