#pragma once
// The convex hull of points in a plane: what a blade's profile covers at the start and the end of
// a frame (sim/blade_stroke.hpp).

#include <Eigen/Core>

#include <cstddef>
#include <span>
#include <vector>

namespace vox::contact {

/// The convex hull of `points`, counter-clockwise, without collinear points (Andrew's monotone
/// chain).
std::vector<Eigen::Vector2d> convex_hull(std::vector<Eigen::Vector2d> points);

/// The same without allocating (a tool's shadow, contact::ToolShape::shadow_area): sorts `points`
/// in place and writes the hull to `hull` (at least twice as long as `points`); returns its
/// number of corners.
std::size_t convex_hull(std::span<Eigen::Vector2d> points, std::span<Eigen::Vector2d> hull) noexcept;

} // namespace vox::contact
