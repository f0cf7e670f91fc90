// An edge of the surface under another edge of it (contact/piece_contact.hpp, EdgeContact): the
// narrow phase. For each pressing edge, the triangles it crosses are found through a grid of
// triangles; an entry and an exit through the two triangles beside one edge make the contact.

#include "contact/patch_geometry.hpp"
#include "contact/piece_contact.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <stdexcept>
#include <utility>
#include <vector>

namespace vox::contact {
namespace {

constexpr std::uint32_t none = ~0u;

/// An edge of the patch with the two triangles beside it.
struct Edge {
    std::uint32_t a = 0, b = 0;
    std::uint32_t left = none, right = none;
};

/// The patch's edges that have exactly two triangles in it, and for each triangle side (3 t + c,
/// the side from corner c to c + 1) its edge among them (none: a rim or non-manifold edge).
std::vector<Edge> two_sided_edges(const SurfacePatch& patch, std::vector<std::uint32_t>& side_edge)
{
    // The sides bucketed by their lower vertex (a counting sort: a whole surface has tens of
    // thousands), then matched by their upper one within a bucket.
    const std::size_t sides = 3 * patch.triangles.size();
    auto end_of = [&](std::size_t side, int k) {
        const Eigen::Vector3i& t = patch.triangles[side / 3];
        const auto c = static_cast<int>(side % 3);
        const auto p = static_cast<std::uint32_t>(t[c]), q = static_cast<std::uint32_t>(t[(c + 1) % 3]);
        return k == 0 ? std::min(p, q) : std::max(p, q);
    };
    std::vector<std::uint32_t> first(patch.start_mm.size() + 1, 0), bucket(sides);
    for (std::size_t i = 0; i < sides; ++i) ++first[end_of(i, 0) + 1];
    for (std::size_t v = 1; v < first.size(); ++v) first[v] += first[v - 1];
    {
        std::vector<std::uint32_t> next(first.begin(), first.end() - 1);
        for (std::size_t i = 0; i < sides; ++i) bucket[next[end_of(i, 0)]++] = static_cast<std::uint32_t>(i);
    }
    std::vector<Edge> edges;
    side_edge.assign(sides, none);
    for (std::size_t v = 0; v + 1 < first.size(); ++v)
        for (std::uint32_t i = first[v]; i < first[v + 1]; ++i) {
            const std::uint32_t high = end_of(bucket[i], 1);
            std::uint32_t count = 0, other = none;
            for (std::uint32_t j = first[v]; j < first[v + 1]; ++j)
                if (j != i && end_of(bucket[j], 1) == high) ++count, other = bucket[j];
            if (count != 1 || other < bucket[i]) continue; // a rim or non-manifold edge; or taken from its other side
            side_edge[bucket[i]] = side_edge[other] = static_cast<std::uint32_t>(edges.size());
            edges.push_back({static_cast<std::uint32_t>(v), high, bucket[i] / 3, other / 3});
        }
    return edges;
}

/// Where segment (p, q) crosses triangle `tri` (unit `normal`) at positions x: its parameter along the segment,
/// and whether it goes in (from the outward side to the inward one). False when it does not cross.
bool crosses(const std::vector<Eigen::Vector3d>& x, const Eigen::Vector3i& tri, const Eigen::Vector3d& normal, const Eigen::Vector3d& p,
             const Eigen::Vector3d& q, double& at, bool& in)
{
    const Eigen::Vector3d& c0 = x[static_cast<std::size_t>(tri[0])];
    const double dp = normal.dot(p - c0), dq = normal.dot(q - c0);
    if (normal.isZero() || !((dp > 0.0 && dq < 0.0) || (dp < 0.0 && dq > 0.0))) return false;
    at = dp / (dp - dq);
    in = dp > 0.0;
    const Eigen::Vector3d point = p + at * (q - p);
    return patch_geometry::covers(patch_geometry::plane_weights(point, c0, x[static_cast<std::size_t>(tri[1])], x[static_cast<std::size_t>(tri[2])]),
                                  patch_geometry::k_on_triangle);
}

/// Parameters (s, t) of the nearest points of segments (p0, p1) and (q0, q1), each in [0, 1];
/// false when the two are near parallel (under about 3 degrees: a face's vertices press there).
bool nearest_points(const Eigen::Vector3d& p0, const Eigen::Vector3d& p1, const Eigen::Vector3d& q0, const Eigen::Vector3d& q1, double& s,
                    double& t)
{
    const Eigen::Vector3d d1 = p1 - p0, d2 = q1 - q0, r = p0 - q0;
    const double a = d1.squaredNorm(), e = d2.squaredNorm(), b = d1.dot(d2), c = d1.dot(r), f = d2.dot(r);
    const double denominator = a * e - b * b;
    if (!(denominator > 2.7e-3 * a * e)) return false; // sin^2 of 3 degrees
    s = std::clamp((b * f - c * e) / denominator, 0.0, 1.0);
    t = std::clamp((b * s + f) / e, 0.0, 1.0);
    s = std::clamp((b * t - c) / a, 0.0, 1.0);
    return true;
}

/// The unit normal along the cross product of edges (p0, p1) and (q0, q1), turned to the side of
/// `outward`; zero when they are near parallel.
Eigen::Vector3d cross_normal(const Eigen::Vector3d& p0, const Eigen::Vector3d& p1, const Eigen::Vector3d& q0, const Eigen::Vector3d& q1,
                             const Eigen::Vector3d& outward)
{
    const Eigen::Vector3d d1 = p1 - p0, d2 = q1 - q0, n = d1.cross(d2);
    const double length = n.norm();
    if (!(length > 0.05 * d1.norm() * d2.norm())) return Eigen::Vector3d::Zero();
    return n.dot(outward) >= 0.0 ? Eigen::Vector3d(n / length) : Eigen::Vector3d(-n / length);
}

} // namespace

namespace patch_geometry {

std::vector<EdgeContact> find_edges(const SurfacePatch& patch, const PieceContactParameters& parameters, const MeasuredTriangles& triangles,
                                    const std::vector<unsigned char>* turned_near)
{
    std::vector<EdgeContact> out;
    if (patch.triangles.empty()) return out;
    std::vector<std::uint32_t> side_edge;
    const std::vector<Edge> edges = two_sided_edges(patch, side_edge);
    const std::size_t triangle_count = patch.triangles.size();
    const std::vector<Eigen::Vector3d>& start_normal = triangles.start_normal;
    const std::vector<Eigen::Vector3d>& end_normal = triangles.end_normal;
    const std::vector<unsigned char>& needle = triangles.needle;
    std::vector<double> vertex_area(patch.start_mm.size(), 0.0); // a third of each of its triangles'
    for (std::size_t t = 0; t < triangle_count; ++t)
        for (int c = 0; c < 3; ++c) vertex_area[static_cast<std::size_t>(patch.triangles[t][c])] += triangles.area[t] / 3.0;
    auto edge_normal = [&](const Edge& e, const std::vector<Eigen::Vector3d>& x) -> Eigen::Vector3d {
        const Eigen::Vector3d n = triangle_normal(patch, x, patch.triangles[e.left]) + triangle_normal(patch, x, patch.triangles[e.right]);
        return n.norm() > 0.0 ? Eigen::Vector3d(n.normalized()) : Eigen::Vector3d::Zero();
    };
    const double depth_limit = parameters.max_depth_mm;
    const double k_per_mm2 = parameters.stiffness_n_per_mm / 100.0;
    const BoxGrid& grid = triangles.grid;
    struct Crossing {
        std::uint32_t triangle;
        double at;
        bool in;
    };
    std::vector<Crossing> crossings;
    std::vector<std::uint32_t> near;
    std::vector<std::uint32_t> seen(triangle_count, none); // per triangle: the edge that last tested it
    std::vector<std::pair<std::uint64_t, EdgeContact>> found; // keyed by the two edges, lower first
    for (std::uint32_t e = 0; e < edges.size(); ++e) {
        const Edge& pressing = edges[e];
        if (!patch.presses[pressing.a] || !patch.presses[pressing.b] || needle[pressing.left] || needle[pressing.right]) continue;
        if (turned_near && !(*turned_near)[pressing.a] && !(*turned_near)[pressing.b] &&
            (patch.start_mm[pressing.b] - patch.start_mm[pressing.a]).norm() <= 2.0 * depth_limit)
            continue;
        const Eigen::Vector3d own_normal = edge_normal(pressing, patch.start_mm);
        if (own_normal.isZero()) continue;
        Eigen::AlignedBox3d box(patch.start_mm[pressing.a]);
        for (const auto* x : {&patch.start_mm, &patch.end_mm}) {
            box.extend((*x)[pressing.a]);
            box.extend((*x)[pressing.b]);
        }
        // The triangles it crosses, at the step's start, else at its predicted end.
        near.clear();
        grid.near(box, [&](std::uint32_t t) {
            if (seen[t] == e) return;
            seen[t] = e;
            const Eigen::Vector3i& tri = patch.triangles[t];
            if (needle[t] || (tri.array() == static_cast<int>(pressing.a)).any() || (tri.array() == static_cast<int>(pressing.b)).any()) return;
            // Within 45 degrees of the edge's own side: the surface it lies in. (A wedge it passes
            // under faces it, its sides' mean normal more than 105 degrees from the edge's: a side
            // within 45 degrees would turn over 60 degrees from that mean, a ridge sharper than
            // the right angles of a voxel surface's corners.)
            if (own_normal.dot(start_normal[t]) > 0.7) return;
            near.push_back(t);
        });
        for (const std::vector<Eigen::Vector3d>* x : {&patch.start_mm, &patch.end_mm}) {
            const std::vector<Eigen::Vector3d>& normal = x == &patch.start_mm ? start_normal : end_normal;
            crossings.clear();
            for (std::uint32_t t : near) {
                double at = 0.0;
                bool in = false;
                if (crosses(*x, patch.triangles[t], normal[t], (*x)[pressing.a], (*x)[pressing.b], at, in)) crossings.push_back({t, at, in});
            }
            bool any = false;
            for (const Crossing& enter : crossings)
                for (const Crossing& leave : crossings) {
                    if (!enter.in || leave.in || !(leave.at > enter.at)) continue;
                    // The two triangles beside one edge: the pressed edge.
                    std::uint32_t shared = none;
                    for (std::uint32_t c = 0; c < 3 && shared == none; ++c)
                        for (std::uint32_t d = 0; d < 3; ++d)
                            if (side_edge[3 * enter.triangle + c] != none && side_edge[3 * enter.triangle + c] == side_edge[3 * leave.triangle + d])
                                shared = side_edge[3 * enter.triangle + c];
                    if (shared == none) continue;
                    const Edge& under = edges[shared];
                    if (under.a == pressing.a || under.a == pressing.b || under.b == pressing.a || under.b == pressing.b) continue;
                    const Eigen::Vector3d under_normal = edge_normal(under, patch.start_mm);
                    if (!(own_normal.dot(under_normal) < k_facing)) continue;
                    EdgeContact c;
                    if (!nearest_points((*x)[pressing.a], (*x)[pressing.b], (*x)[under.a], (*x)[under.b], c.s, c.t)) continue;
                    // Depth along the two edges' normal, out of the pressed side, at a pose.
                    auto depth_at = [&](const std::vector<Eigen::Vector3d>& y, const Eigen::Vector3d& outward, Eigen::Vector3d* normal) {
                        const Eigen::Vector3d n = cross_normal(y[pressing.a], y[pressing.b], y[under.a], y[under.b], outward);
                        if (normal) *normal = n;
                        const Eigen::Vector3d p = (1.0 - c.s) * y[pressing.a] + c.s * y[pressing.b];
                        const Eigen::Vector3d q = (1.0 - c.t) * y[under.a] + c.t * y[under.b];
                        return n.isZero() ? std::nan("") : -n.dot(p - q);
                    };
                    const double d0 = depth_at(patch.start_mm, under_normal, &c.normal);
                    const double d1 = depth_at(patch.end_mm, edge_normal(under, patch.end_mm), nullptr);
                    if (!(d0 <= depth_limit) || (d0 < -parameters.skin_mm && !(d1 > 0.0))) continue;
                    // Through material: under the pressed edge at rest already.
                    const double rest = depth_at(patch.rest_mm, c.normal, nullptr);
                    if (rest > parameters.rest_tolerance_mm) continue;
                    c.edge = {pressing.a, pressing.b};
                    c.pressed = {under.a, under.b};
                    c.depth_mm = d0;
                    c.area_mm2 = (leave.at - enter.at) * (vertex_area[pressing.a] + vertex_area[pressing.b]) / 6.0;
                    c.stiffness_n_per_mm = k_per_mm2 * c.area_mm2;
                    c.force_n = c.stiffness_n_per_mm * c.depth_mm;
                    const std::uint64_t key = (std::uint64_t{std::min(e, shared)} << 32) | std::max(e, shared);
                    found.emplace_back(key, c);
                    any = true;
                }
            if (any) break; // in at the start: the end is not looked at
        }
    }
    // Each pair of edges once, its deepest.
    std::stable_sort(found.begin(), found.end(), [](const auto& p, const auto& q) {
        return p.first != q.first ? p.first < q.first : p.second.depth_mm > q.second.depth_mm;
    });
    for (std::size_t i = 0; i < found.size(); ++i)
        if (i == 0 || found[i].first != found[i - 1].first) out.push_back(found[i].second);
    return out;
}

} // namespace patch_geometry

std::vector<EdgeContact> edge_contacts(const SurfacePatch& patch, const PieceContactParameters& parameters)
{
    patch_geometry::check(patch, "edge_contacts");
    return patch_geometry::find_edges(patch, parameters, patch_geometry::measure(patch, parameters.max_depth_mm), nullptr);
}

} // namespace vox::contact
