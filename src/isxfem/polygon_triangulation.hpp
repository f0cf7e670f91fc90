#pragma once
// Triangulation of a simple polygon by ear clipping (O(n^2)), holes bridged into the polygons
// around them, and points added inside a triangulation (split, then Lawson's flips around them),
// for the faces that close a cut.

#include <Eigen/Core>

#include <array>
#include <vector>

namespace vox::isxfem {

/// Triangles (indices into `polygon`, counter-clockwise) covering the simple polygon given in
/// either orientation; n - 2 of them. A polygon that is not simple gets what ear clipping can
/// find, then a fan over the rest. `apart` (optional, per vertex): diagonals joining two flagged
/// vertices are avoided where another ear will do.
std::vector<std::array<int, 3>> triangulate_polygon(const std::vector<Eigen::Vector2d>& polygon, const std::vector<bool>& apart = {});

/// Where a point falls in a triangulation (counter-clockwise triangles, indices into the points).
struct Location {
    int triangle = -1; ///< -1: in none (or on the triangulated polygon's boundary)
    int edge = -1;     ///< the triangle's edge it lies on (from corner `edge` to the next), or -1: clear of all three
    int across = -1;   ///< on an edge: the triangle on its other side
};

/// The triangle that holds p, and whether p lies on one of its edges (within a hundredth of its
/// longest edge) that another triangle shares.
Location locate(const std::vector<Eigen::Vector2d>& points, const std::vector<std::array<int, 3>>& triangles, const Eigen::Vector2d& p);

/// Adds p to the triangulation where locate() found it: the triangle is split in three (or, p on
/// an edge, it and the triangle across in two each) and the edges opposite p are flipped while
/// the point across lies in their circumcircle (Lawson), except the boundary's (the polygon
/// points[0 .. boundary - 1] in order, bridges included): the triangles around p come out locally
/// Delaunay, the rest as they were. p is appended to `points`.
void insert_point(std::vector<Eigen::Vector2d>& points, std::vector<std::array<int, 3>>& triangles, const Location& where,
                  const Eigen::Vector2d& p, std::size_t boundary);

/// A corner of one of several loops.
struct LoopCorner {
    std::size_t loop = 0, corner = 0;
};

/// Faces from closed loops in a plane: each counter-clockwise loop bounds a face, each clockwise
/// one is a hole in the smallest face around it. Per face, its corners in order with its holes
/// joined in, rightmost hole first, each by a bridge from its rightmost corner to the nearest
/// corner of the face that it sees without crossing an edge, walked both ways (the bridge's ends
/// appear twice). `left_out` counts holes in no face or with no bridge.
std::vector<std::vector<LoopCorner>> faces_with_holes(const std::vector<std::vector<Eigen::Vector2d>>& loops, std::size_t& left_out);

} // namespace vox::isxfem
