#pragma once
// The convex hull of points in a plane: what a blade's profile covers at the start and the end of
// a frame (sim/blade_stroke.hpp).

#include <Eigen/Core>

#include <vector>

namespace vox::contact {

/// The convex hull of `points`, counter-clockwise, without collinear points (Andrew's monotone
/// chain).
std::vector<Eigen::Vector2d> convex_hull(std::vector<Eigen::Vector2d> points);

} // namespace vox::contact
