#include "contact/piece_contact.hpp"

#include "contact/box_grid.hpp"

#include <Eigen/Geometry>

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <utility>

namespace vox::contact {
namespace {

/// Weights of the point of triangle (a, b, c) nearest to p's projection on its plane (unclamped:
/// negative outside the triangle).
std::array<double, 3> plane_weights(const Eigen::Vector3d& p, const Eigen::Vector3d& a, const Eigen::Vector3d& b, const Eigen::Vector3d& c)
{
    const Eigen::Vector3d e0 = b - a, e1 = c - a, r = p - a;
    const double d00 = e0.dot(e0), d01 = e0.dot(e1), d11 = e1.dot(e1), d20 = r.dot(e0), d21 = r.dot(e1);
    const double det = d00 * d11 - d01 * d01;
    if (!(det > 0.0)) return {-1.0, -1.0, -1.0}; // a degenerate triangle presses nothing
    const double wb = (d11 * d20 - d01 * d21) / det, wc = (d00 * d21 - d01 * d20) / det;
    return {1.0 - wb - wc, wb, wc};
}

bool covers(const std::array<double, 3>& w, double tolerance) { return w[0] >= -tolerance && w[1] >= -tolerance && w[2] >= -tolerance; }

/// The triangles' boxes, each swept from its start to its end, in a grid whose cells are about two
/// edges wide (at least `min_cell_mm`).
BoxGrid triangle_grid(const SurfacePatch& patch, double min_cell_mm)
{
    double edges = 0.0;
    std::vector<Eigen::AlignedBox3d> boxes(patch.triangles.size());
    for (std::size_t i = 0; i < patch.triangles.size(); ++i) {
        const Eigen::Vector3i& t = patch.triangles[i];
        edges += (patch.start_mm[static_cast<std::size_t>(t[1])] - patch.start_mm[static_cast<std::size_t>(t[0])]).norm();
        boxes[i].setEmpty();
        for (int c = 0; c < 3; ++c) {
            boxes[i].extend(patch.start_mm[static_cast<std::size_t>(t[c])]);
            boxes[i].extend(patch.end_mm[static_cast<std::size_t>(t[c])]);
        }
    }
    const double cell = std::max({2.0 * edges / static_cast<double>(std::max<std::size_t>(1, patch.triangles.size())), min_cell_mm, 1e-6});
    return BoxGrid(std::move(boxes), cell);
}

/// Outward unit normal of triangle t with corners in `x` (zero when degenerate).
Eigen::Vector3d triangle_normal(const SurfacePatch& patch, const std::vector<Eigen::Vector3d>& x, const Eigen::Vector3i& t)
{
    const Eigen::Vector3d& a = x[static_cast<std::size_t>(t[0])];
    const Eigen::Vector3d n = (x[static_cast<std::size_t>(t[1])] - a).cross(x[static_cast<std::size_t>(t[2])] - a);
    const double length = n.norm();
    return length > 0.0 ? Eigen::Vector3d(patch.outward_sign * n / length) : Eigen::Vector3d::Zero();
}

} // namespace

std::vector<FaceContact> face_contacts(const SurfacePatch& patch, const PieceContactParameters& parameters)
{
    const std::size_t n = patch.start_mm.size();
    if (patch.end_mm.size() != n || patch.rest_mm.size() != n || patch.presses.size() != n)
        throw std::invalid_argument("contact::face_contacts: the patch's per-vertex arrays differ in length");
    for (const Eigen::Vector3i& t : patch.triangles)
        if (t.minCoeff() < 0 || static_cast<std::size_t>(t.maxCoeff()) >= n)
            throw std::invalid_argument("contact::face_contacts: a triangle's corner is not a vertex of the patch");
    std::vector<FaceContact> out;
    if (patch.triangles.empty()) return out;
    const double depth = parameters.max_depth_mm;
    const BoxGrid grid = triangle_grid(patch, 2.0 * depth); // cells about as wide as a vertex's reach: few lookups a vertex
    constexpr double facing = -0.25;   // cos 105 degrees
    constexpr double on_triangle = 0.02; // weights this far below zero still press the triangle (its edges)
    const double k_per_mm2 = parameters.stiffness_n_per_mm / 100.0;
    const std::size_t triangle_count = patch.triangles.size();
    std::vector<Eigen::Vector3d> start_normal(triangle_count), end_normal(triangle_count), rest_normal(triangle_count);
    std::vector<double> area(triangle_count);
    std::vector<unsigned char> needle(triangle_count, 0);
    std::vector<Eigen::Vector3d> vertex_normal(n, Eigen::Vector3d::Zero());
    std::vector<std::uint32_t> first(n + 1, 0), around(3 * triangle_count); // each vertex's triangles
    for (std::size_t t = 0; t < triangle_count; ++t) {
        const Eigen::Vector3i& tri = patch.triangles[t];
        const Eigen::Vector3d& a = patch.start_mm[static_cast<std::size_t>(tri[0])];
        area[t] = 0.5 * (patch.start_mm[static_cast<std::size_t>(tri[1])] - a).cross(patch.start_mm[static_cast<std::size_t>(tri[2])] - a).norm();
        start_normal[t] = triangle_normal(patch, patch.start_mm, tri);
        end_normal[t] = triangle_normal(patch, patch.end_mm, tri);
        rest_normal[t] = triangle_normal(patch, patch.rest_mm, tri);
        // A needle at rest (height under 5 % of its longest edge: where a cut's closure splits a
        // long surface triangle along the crossing, two of its corners can share a rest point)
        // has no direction of its own to press along: its deformed normal points anywhere, and a
        // vertex a voxel away was pushed through it (an Is-XFEM bracket's crack walls).
        const Eigen::Vector3d& r0 = patch.rest_mm[static_cast<std::size_t>(tri[0])];
        const Eigen::Vector3d& r1 = patch.rest_mm[static_cast<std::size_t>(tri[1])];
        const Eigen::Vector3d& r2 = patch.rest_mm[static_cast<std::size_t>(tri[2])];
        const double longest = std::max({(r1 - r0).squaredNorm(), (r2 - r1).squaredNorm(), (r0 - r2).squaredNorm()});
        needle[t] = (r1 - r0).cross(r2 - r0).norm() < 5e-2 * longest;
        for (int c = 0; c < 3; ++c) {
            vertex_normal[static_cast<std::size_t>(tri[c])] += area[t] * start_normal[t];
            ++first[static_cast<std::size_t>(tri[c]) + 1];
        }
    }
    for (std::size_t v = 0; v < n; ++v) first[v + 1] += first[v];
    {
        std::vector<std::uint32_t> next(first.begin(), first.end() - 1);
        for (std::uint32_t t = 0; t < triangle_count; ++t)
            for (int c = 0; c < 3; ++c) around[next[static_cast<std::size_t>(patch.triangles[t][c])]++] = t;
    }
    for (Eigen::Vector3d& normal : vertex_normal)
        if (normal.norm() > 0.0) normal.normalize();
    std::vector<std::uint32_t> seen(triangle_count, ~0u); // per triangle: the vertex that last tested it
    for (std::uint32_t v = 0; v < n; ++v) {
        if (!patch.presses[v] || vertex_normal[v].isZero()) continue;
        Eigen::AlignedBox3d box(patch.start_mm[v]);
        box.extend(patch.end_mm[v]);
        box.min().array() -= depth; // a vertex up to max_depth behind a triangle presses it
        box.max().array() += depth;
        FaceContact best;
        double best_depth = 0.0;
        bool found = false;
        grid.near(box, [&](std::uint32_t t) {
            if (seen[t] == v) return;
            seen[t] = v;
            const Eigen::Vector3i& tri = patch.triangles[t];
            if (needle[t] || tri[0] == static_cast<int>(v) || tri[1] == static_cast<int>(v) || tri[2] == static_cast<int>(v)) return;
            const Eigen::Vector3d& n0 = start_normal[t];
            if (!(vertex_normal[v].dot(n0) < facing)) return;
            auto corner = [&](const std::vector<Eigen::Vector3d>& x, int c) -> const Eigen::Vector3d& { return x[static_cast<std::size_t>(tri[c])]; };
            const double p0 = -n0.dot(patch.start_mm[v] - corner(patch.start_mm, 0));
            const double p1 = -end_normal[t].dot(patch.end_mm[v] - corner(patch.end_mm, 0));
            // Deeper than max_depth at the start: gone through, or the far side of a thin part.
            // Apart by more than the skin and not predicted to come in during the step: no contact.
            if (p0 > depth || (p0 < -parameters.skin_mm && !(p1 > 0.0))) return;
            // Where the vertex presses: on the triangle at the pose it is deeper in.
            const std::vector<Eigen::Vector3d>& at = p0 >= p1 ? patch.start_mm : patch.end_mm;
            std::array<double, 3> w = plane_weights(at[v], corner(at, 0), corner(at, 1), corner(at, 2));
            if (!covers(w, on_triangle)) return;
            // Through material: behind the triangle in the rest shape already.
            const double rest_distance = rest_normal[t].dot(patch.rest_mm[v] - corner(patch.rest_mm, 0));
            if (rest_distance < -parameters.rest_tolerance_mm &&
                covers(plane_weights(patch.rest_mm[v], corner(patch.rest_mm, 0), corner(patch.rest_mm, 1), corner(patch.rest_mm, 2)), on_triangle))
                return;
            // Ranked by the deeper of its two depths (a vertex arriving counts by where it would end).
            if (found && !(std::max(p0, p1) > best_depth)) return;
            found = true;
            best_depth = std::max(p0, p1);
            for (double& x : w) x = std::clamp(x, 0.0, 1.0);
            const double sum = w[0] + w[1] + w[2];
            for (double& x : w) x /= sum;
            // The area the vertex stands for, as it faces the triangle: a third of each of its
            // triangles' areas, projected on the triangle's plane (a vertex on a block's edge
            // presses with its bottom face's share, not its side's), and half of it (see the header).
            double pressing = 0.0;
            for (std::uint32_t k = first[v]; k < first[v + 1]; ++k)
                pressing += area[around[k]] / 3.0 * std::max(0.0, -start_normal[around[k]].dot(n0));
            pressing *= 0.5;
            best.vertex = v;
            best.triangle = t;
            best.weights = w;
            best.normal = n0;
            best.depth_mm = p0;
            best.area_mm2 = pressing;
            best.force_n = k_per_mm2 * pressing * best.depth_mm;
            best.stiffness_n_per_mm = k_per_mm2 * pressing;
        });
        if (found) out.push_back(best);
    }
    return out;
}

} // namespace vox::contact
