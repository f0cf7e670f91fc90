#include "contact/piece_contact.hpp"

#include "contact/patch_geometry.hpp"

#include <Eigen/Geometry>

#include <algorithm>
#include <cmath>
#include <utility>

namespace vox::contact {

namespace patch_geometry {

std::vector<FaceContact> find_faces(const SurfacePatch& patch, const PieceContactParameters& parameters, const MeasuredTriangles& triangles,
                                    std::vector<unsigned char>* turned_near)
{
    const std::size_t n = patch.start_mm.size();
    std::vector<FaceContact> out;
    if (turned_near) turned_near->assign(n, 0);
    if (patch.triangles.empty()) return out;
    const double depth = parameters.max_depth_mm;
    const BoxGrid& grid = triangles.grid; // cells about as wide as a vertex's reach: few lookups a vertex
    const double k_per_mm2 = parameters.stiffness_n_per_mm / 100.0;
    const std::size_t triangle_count = patch.triangles.size();
    const std::vector<Eigen::Vector3d>& start_normal = triangles.start_normal;
    const std::vector<Eigen::Vector3d>& end_normal = triangles.end_normal;
    const std::vector<Eigen::Vector3d>& rest_normal = triangles.rest_normal;
    const std::vector<double>& area = triangles.area;
    const std::vector<unsigned char>& needle = triangles.needle;
    std::vector<Eigen::Vector3d> vertex_normal(n, Eigen::Vector3d::Zero());
    std::vector<std::uint32_t> first(n + 1, 0), around(3 * triangle_count); // each vertex's triangles
    for (std::size_t t = 0; t < triangle_count; ++t) {
        const Eigen::Vector3i& tri = patch.triangles[t];
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
            if (turned_near && !(*turned_near)[v] && vertex_normal[v].dot(n0) < 0.0 && grid.boxes()[t].intersects(box)) (*turned_near)[v] = 1;
            if (!(vertex_normal[v].dot(n0) < k_facing)) return;
            auto corner = [&](const std::vector<Eigen::Vector3d>& x, int c) -> const Eigen::Vector3d& { return x[static_cast<std::size_t>(tri[c])]; };
            const double p0 = -n0.dot(patch.start_mm[v] - corner(patch.start_mm, 0));
            const double p1 = -end_normal[t].dot(patch.end_mm[v] - corner(patch.end_mm, 0));
            // Deeper than max_depth at the start: gone through, or the far side of a thin part.
            // Apart by more than the skin and not predicted to come in during the step: no contact.
            if (p0 > depth || (p0 < -parameters.skin_mm && !(p1 > 0.0))) return;
            // Where the vertex presses: on the triangle at the pose it is deeper in.
            const std::vector<Eigen::Vector3d>& at = p0 >= p1 ? patch.start_mm : patch.end_mm;
            std::array<double, 3> w = plane_weights(at[v], corner(at, 0), corner(at, 1), corner(at, 2));
            if (!covers(w, k_on_triangle)) return;
            // Through material: behind the triangle in the rest shape already.
            const double rest_distance = rest_normal[t].dot(patch.rest_mm[v] - corner(patch.rest_mm, 0));
            if (rest_distance < -parameters.rest_tolerance_mm &&
                covers(plane_weights(patch.rest_mm[v], corner(patch.rest_mm, 0), corner(patch.rest_mm, 1), corner(patch.rest_mm, 2)), k_on_triangle))
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

} // namespace patch_geometry

std::vector<FaceContact> face_contacts(const SurfacePatch& patch, const PieceContactParameters& parameters)
{
    patch_geometry::check(patch, "face_contacts");
    return patch_geometry::find_faces(patch, parameters, patch_geometry::measure(patch, parameters.max_depth_mm), nullptr);
}

SurfaceContacts surface_contacts(const SurfacePatch& patch, const PieceContactParameters& parameters)
{
    patch_geometry::check(patch, "surface_contacts");
    const patch_geometry::MeasuredTriangles triangles = patch_geometry::measure(patch, parameters.max_depth_mm);
    std::vector<unsigned char> turned_near;
    SurfaceContacts out;
    out.faces = patch_geometry::find_faces(patch, parameters, triangles, &turned_near);
    out.edges = patch_geometry::find_edges(patch, parameters, triangles, &turned_near);
    return out;
}

} // namespace vox::contact
