#pragma once
// What the two narrow phases of the surface's contact with itself (contact/piece_contact.cpp, a
// vertex against a face; contact/piece_edge_contact.cpp, an edge under an edge) both measure of a
// patch: its triangles' normals and the grid they are found through, and the tests they share.

#include "contact/box_grid.hpp"
#include "contact/piece_contact.hpp"

#include <Eigen/Geometry>

#include <algorithm>
#include <array>
#include <stdexcept>
#include <string>
#include <vector>

namespace vox::contact::patch_geometry {

/// Two surface parts face each other when their normals are more than 105 degrees apart, so a
/// voxel surface's corners and steps never catch themselves.
inline constexpr double k_facing = -0.25; // cos 105 degrees
/// Weights this far below zero still count as on the triangle (its edges).
inline constexpr double k_on_triangle = 0.02;

/// Throws std::invalid_argument, naming `who`, when the patch's arrays differ in length or a
/// triangle's corner is not one of its vertices.
inline void check(const SurfacePatch& patch, const char* who)
{
    const std::size_t n = patch.start_mm.size();
    if (patch.end_mm.size() != n || patch.rest_mm.size() != n || patch.presses.size() != n)
        throw std::invalid_argument(std::string("contact::") + who + ": the patch's per-vertex arrays differ in length");
    for (const Eigen::Vector3i& t : patch.triangles)
        if (t.minCoeff() < 0 || static_cast<std::size_t>(t.maxCoeff()) >= n)
            throw std::invalid_argument(std::string("contact::") + who + ": a triangle's corner is not a vertex of the patch");
}

/// Weights of the point of triangle (a, b, c) nearest to p's projection on its plane (unclamped:
/// negative outside the triangle).
inline std::array<double, 3> plane_weights(const Eigen::Vector3d& p, const Eigen::Vector3d& a, const Eigen::Vector3d& b, const Eigen::Vector3d& c)
{
    const Eigen::Vector3d e0 = b - a, e1 = c - a, r = p - a;
    const double d00 = e0.dot(e0), d01 = e0.dot(e1), d11 = e1.dot(e1), d20 = r.dot(e0), d21 = r.dot(e1);
    const double det = d00 * d11 - d01 * d01;
    if (!(det > 0.0)) return {-1.0, -1.0, -1.0}; // a degenerate triangle presses nothing
    const double wb = (d11 * d20 - d01 * d21) / det, wc = (d00 * d21 - d01 * d20) / det;
    return {1.0 - wb - wc, wb, wc};
}

inline bool covers(const std::array<double, 3>& w, double tolerance) { return w[0] >= -tolerance && w[1] >= -tolerance && w[2] >= -tolerance; }

/// The triangles' boxes, each swept from its start to its end, in a grid whose cells are about two
/// edges wide (at least `min_cell_mm`).
inline BoxGrid triangle_grid(const SurfacePatch& patch, double min_cell_mm)
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
inline Eigen::Vector3d triangle_normal(const SurfacePatch& patch, const std::vector<Eigen::Vector3d>& x, const Eigen::Vector3i& t)
{
    const Eigen::Vector3d& a = x[static_cast<std::size_t>(t[0])];
    const Eigen::Vector3d n = (x[static_cast<std::size_t>(t[1])] - a).cross(x[static_cast<std::size_t>(t[2])] - a);
    const double length = n.norm();
    return length > 0.0 ? Eigen::Vector3d(patch.outward_sign * n / length) : Eigen::Vector3d::Zero();
}

/// Whether triangle t is a needle at rest: under 5 % as high as its longest edge. Where a cut's
/// closure splits a long surface triangle along the crossing, two of its corners can share a rest
/// point; such a triangle has no direction of its own to press along (its deformed normal points
/// anywhere, and a vertex a voxel away was pushed through one: an Is-XFEM bracket's crack walls).
inline bool is_needle(const SurfacePatch& patch, const Eigen::Vector3i& t)
{
    const Eigen::Vector3d& r0 = patch.rest_mm[static_cast<std::size_t>(t[0])];
    const Eigen::Vector3d& r1 = patch.rest_mm[static_cast<std::size_t>(t[1])];
    const Eigen::Vector3d& r2 = patch.rest_mm[static_cast<std::size_t>(t[2])];
    const double longest = std::max({(r1 - r0).squaredNorm(), (r2 - r1).squaredNorm(), (r0 - r2).squaredNorm()});
    return (r1 - r0).cross(r2 - r0).norm() < 5e-2 * longest;
}

/// A patch's triangles measured once for both phases: outward normals at the step's start, end
/// and rest, areas at the start, which are needles, and the grid of their swept boxes (cells about
/// two edges wide, at least twice the contact's depth: about a vertex's reach).
struct MeasuredTriangles {
    std::vector<Eigen::Vector3d> start_normal, end_normal, rest_normal;
    std::vector<double> area;
    std::vector<unsigned char> needle;
    BoxGrid grid;
};

inline MeasuredTriangles measure(const SurfacePatch& patch, double max_depth_mm)
{
    const std::size_t count = patch.triangles.size();
    std::vector<Eigen::Vector3d> start(count), end(count), rest(count);
    std::vector<double> area(count);
    std::vector<unsigned char> needle(count);
    for (std::size_t t = 0; t < count; ++t) {
        const Eigen::Vector3i& tri = patch.triangles[t];
        const Eigen::Vector3d& a = patch.start_mm[static_cast<std::size_t>(tri[0])];
        area[t] = 0.5 * (patch.start_mm[static_cast<std::size_t>(tri[1])] - a).cross(patch.start_mm[static_cast<std::size_t>(tri[2])] - a).norm();
        start[t] = triangle_normal(patch, patch.start_mm, tri);
        end[t] = triangle_normal(patch, patch.end_mm, tri);
        rest[t] = triangle_normal(patch, patch.rest_mm, tri);
        needle[t] = is_needle(patch, tri);
    }
    return {std::move(start), std::move(end), std::move(rest), std::move(area), std::move(needle), triangle_grid(patch, 2.0 * max_depth_mm)};
}

/// The two phases on measured triangles (contact/piece_contact.cpp, contact/piece_edge_contact.cpp);
/// `turned_near` as surface_contacts says.
std::vector<FaceContact> find_faces(const SurfacePatch& patch, const PieceContactParameters& parameters, const MeasuredTriangles& triangles,
                                    std::vector<unsigned char>* turned_near);
std::vector<EdgeContact> find_edges(const SurfacePatch& patch, const PieceContactParameters& parameters, const MeasuredTriangles& triangles,
                                    const std::vector<unsigned char>* turned_near);

} // namespace vox::contact::patch_geometry
