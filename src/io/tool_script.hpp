#pragma once
// Where the scene's script puts a tool at a simulated time (docs/scene-format.md, "script").

#include "io/scene.hpp"

#include <Eigen/Core>
#include <Eigen/Geometry>

#include <cstddef>
#include <limits>

namespace vox::io {

/// A tool's pose: the rigid motion from the tool's own frame to the world frame.
struct ToolPose {
    /// False when the script has no entry for the tool: it is nowhere, and the other members keep
    /// their defaults.
    bool placed = false;
    /// Position of the tool's origin, world mm; NaN when not placed.
    Eigen::Vector3d position_mm = Eigen::Vector3d::Constant(std::numeric_limits<double>::quiet_NaN());
    /// Rotation from the tool's frame to the world frame, unit quaternion; identity when not placed.
    Eigen::Quaterniond orientation = Eigen::Quaterniond::Identity();
};

/// The pose of scene.tools[tool_index] at simulated time t_s (s), from its script entries alone
/// (entries of other tools are skipped):
/// - between two entries at times t0 < t1, position linear and orientation slerped (constant
///   angular speed about one axis, the shorter way) with a = (t_s - t0) / (t1 - t0);
/// - at or before its first entry, the first entry's pose; at or after its last, the last's;
/// - two entries at the same time t: the earlier one ends the motion before t, the later one
///   holds from t on (a jump);
/// - no entry at all: placed = false.
/// Throws std::out_of_range when tool_index is not an index into scene.tools.
[[nodiscard]] ToolPose tool_pose(const Scene& scene, std::size_t tool_index, double t_s);

} // namespace vox::io
