#include "haptics/spacemouse_report.hpp"

#include <algorithm>
#include <cstdlib>

namespace vox::haptics {
namespace {

std::int16_t int16_le(std::span<const std::uint8_t> bytes, std::size_t at)
{
    return static_cast<std::int16_t>(static_cast<std::uint16_t>(bytes[at] | (bytes[at + 1] << 8)));
}

} // namespace

bool parse_spacemouse_report(std::span<const std::uint8_t> report, SixAxisState& state)
{
    if (report.empty()) return false;
    switch (report[0]) {
    case 1:
        if (report.size() >= 13) { // all six axes in one report
            for (std::size_t a = 0; a < 6; ++a) state.axes[a] = int16_le(report, 1 + 2 * a);
            return true;
        }
        if (report.size() >= 7) {
            for (std::size_t a = 0; a < 3; ++a) state.axes[a] = int16_le(report, 1 + 2 * a);
            return true;
        }
        return false;
    case 2:
        if (report.size() < 7) return false;
        for (std::size_t a = 0; a < 3; ++a) state.axes[3 + a] = int16_le(report, 1 + 2 * a);
        return true;
    case 3: {
        if (report.size() < 2) return false;
        std::uint32_t buttons = 0;
        for (std::size_t b = 1; b < std::min<std::size_t>(report.size(), 5); ++b) buttons |= std::uint32_t{report[b]} << (8 * (b - 1));
        state.buttons = buttons;
        return true;
    }
    default:
        return false;
    }
}

std::array<double, 6> map_axes(const SixAxisState& state, const AxisMapping& mapping)
{
    std::array<double, 6> out{};
    for (std::size_t a = 0; a < 6; ++a) {
        const int raw = state.axes[static_cast<std::size_t>(std::clamp(mapping.source[a], 0, 5))];
        if (std::abs(raw) <= mapping.dead_zone) continue;
        // Continuous at the dead zone's edge: the range beyond it maps onto (0, 1].
        const double beyond = std::abs(raw) - mapping.dead_zone;
        const double value = std::min(1.0, beyond / std::max(1.0, mapping.full_scale - mapping.dead_zone));
        out[a] = (raw < 0 ? -value : value) * (mapping.sign[a] < 0 ? -1.0 : 1.0);
    }
    return out;
}

} // namespace vox::haptics
