#pragma once
// The surface near a device's tool as the simulation thread publishes it for the 1 kHz loop, once
// a frame: the points the contact presses, how far the tool may move before each can matter
// (contact::measure_slack), and, where the tool asks for haptic subdivision and the method
// measures its compliance at the tool's contact, the subdivided patch there
// (contact/contact_patch.hpp). Headless device runs, the viewer and the haptics bench publish it
// the same way.

#include "contact/surface_points.hpp"
#include "contact/tool_shape.hpp"
#include "io/scene.hpp"
#include "sim/method.hpp"

namespace vox::sim {

/// How far beyond the tool's pushing shape a snapshot reaches, mm: what the device can move into
/// during one frame.
constexpr double k_snapshot_margin_mm = 5.0;

/// Fills `out` with the surface within `box` (world mm) as scene tool `tool` (`spec`), placed at
/// `pose` in the simulation, touches it; stamps it with the simulated time `t_s`.
void take_snapshot(Method& method, std::size_t tool, const io::ToolSpec& spec, const contact::PlacedShape& pose, const Eigen::AlignedBox3d& box,
                   double t_s, contact::SurfacePoints& out);

} // namespace vox::sim
