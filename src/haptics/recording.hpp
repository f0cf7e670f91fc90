#pragma once
// Recordings of a haptic session: one row per 1 ms tick and device with the device's pose and
// buttons read and the force sent, and which tool it drove (docs/recording-format.md). Numbers are written with 17 significant digits, so a
// replay reads back exactly what was recorded and reproduces the same run bit for bit.

#include "haptics/device.hpp"

#include <filesystem>
#include <string>
#include <vector>

namespace vox::haptics {

struct RecordedTick {
    DeviceState state;
    Eigen::Vector3d force_n = Eigen::Vector3d::Zero();
    int level = 0;            ///< the level the simulation ran at (0: not recorded, as in older recordings)
    std::string level_change; ///< on the first tick after the simulation moved to `level`: why (no commas)
    int device = 0;           ///< which of the session's devices (0 in single-device recordings)
    std::string tool;         ///< the scene tool it drove (empty in recordings made before several devices)
};

/// The most devices a recording (and a session) holds.
inline constexpr int k_max_devices = 8;

/// Devices in a recording (one more than the highest device number).
[[nodiscard]] int recorded_devices(const std::vector<RecordedTick>& ticks);
/// Device `device`'s ticks, in order.
[[nodiscard]] std::vector<RecordedTick> device_ticks(const std::vector<RecordedTick>& ticks, int device);

/// Writes atomically (a temporary file renamed into place).
void write_recording(const std::filesystem::path& path, const std::vector<RecordedTick>& ticks);
/// Throws InputError naming the file and line for anything malformed (header, field count,
/// non-numbers, non-finite values, time going backwards, a level or device that is not a whole
/// number in range). Recordings without the level columns (written before them) read with level
/// 0, those without the device columns as device 0 with no tool named.
[[nodiscard]] std::vector<RecordedTick> read_recording(const std::filesystem::path& path);

/// Plays a recording back: the state of the last tick at or before the asked time.
class ReplayDevice final : public Device {
public:
    explicit ReplayDevice(std::vector<RecordedTick> ticks);
    [[nodiscard]] std::string name() const override { return "replay"; }
    [[nodiscard]] const DeviceLimits& limits() const override { return m_limits; }
    bool read(double t_s, DeviceState& state) noexcept override;
    [[nodiscard]] const std::vector<RecordedTick>& ticks() const { return m_ticks; }

private:
    std::vector<RecordedTick> m_ticks;
    DeviceLimits m_limits;
    std::size_t m_cursor = 0;
};

} // namespace vox::haptics
