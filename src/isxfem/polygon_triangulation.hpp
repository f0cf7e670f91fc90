#pragma once
// Triangulation of a simple polygon by ear clipping (O(n^2)), for the faces that close a cut.

#include <Eigen/Core>

#include <array>
#include <vector>

namespace vox::isxfem {

/// Triangles (indices into `polygon`, counter-clockwise) covering the simple polygon given in
/// either orientation; n - 2 of them. A polygon that is not simple gets what ear clipping can
/// find, then a fan over the rest. `apart` (optional, per vertex): diagonals joining two flagged
/// vertices are avoided where another ear will do.
std::vector<std::array<int, 3>> triangulate_polygon(const std::vector<Eigen::Vector2d>& polygon, const std::vector<bool>& apart = {});

} // namespace vox::isxfem
