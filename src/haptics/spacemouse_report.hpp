#pragma once
// HID input reports of 6-DoF controllers of the SpaceMouse class, and their mapping to a motion.
// Older devices send report 1 (translation x, y, z), report 2 (rotation rx, ry, rz), each three
// little-endian int16 after the report id, and report 3 (buttons, a bit mask); newer ones send a
// single 13-byte report 1 with all six axes. Raw axes are mapped through a per-device axis table
// (which raw axis, which sign) and a dead zone, then scaled to [-1, 1].

#include <array>
#include <cstdint>
#include <span>

namespace vox::haptics {

/// The last values of the six raw axes and the buttons.
struct SixAxisState {
    std::array<std::int16_t, 6> axes{}; ///< tx, ty, tz, rx, ry, rz as the device reports them
    std::uint32_t buttons = 0;
};

/// Updates `state` from one input report (report id first); false for a report this parser does
/// not know (other ids, wrong lengths), leaving `state` unchanged.
bool parse_spacemouse_report(std::span<const std::uint8_t> report, SixAxisState& state);

struct AxisMapping {
    std::array<int, 6> source{0, 1, 2, 3, 4, 5};  ///< raw axis feeding each output axis
    std::array<int, 6> sign{1, 1, 1, 1, 1, 1};    ///< +1 or -1 per output axis
    int dead_zone = 16;                            ///< raw counts around zero that read as zero
    double full_scale = 350.0;                     ///< raw counts that read as 1 (clamped beyond)
};

/// The six output axes in [-1, 1]: translation x, y, z then rotation x, y, z.
[[nodiscard]] std::array<double, 6> map_axes(const SixAxisState& state, const AxisMapping& mapping);

} // namespace vox::haptics
