#pragma once
// The mouse and keyboard as a 3-DoF device (no force output): the viewer's input thread sets
// the position it points at, the haptic loop reads the newest one, neither waits (a triple
// buffer). The device glides there at most 1 mm a tick (1 m/s): a click far away must not move
// the tool further in one tick than the surface snapshot around it reaches. Used when no haptic
// device is present.

#include "haptics/device.hpp"
#include "haptics/triple_buffer.hpp"

namespace vox::haptics {

class PointerDevice final : public Device {
public:
    /// Starts at `start_mm`; the tool keeps `orientation` (a 3-DoF device does not turn it).
    PointerDevice(const Eigen::Vector3d& start_mm, const Eigen::Quaterniond& orientation);
    [[nodiscard]] std::string name() const override { return "mouse and keyboard (3-DoF, no force)"; }
    [[nodiscard]] const DeviceLimits& limits() const override { return m_limits; }
    bool read(double t_s, DeviceState& state) noexcept override;

    /// Input thread: the tool's position from now on, world mm.
    void point_at(const Eigen::Vector3d& position_mm) noexcept;
    /// Input thread: the last position given.
    [[nodiscard]] const Eigen::Vector3d& pointed() const noexcept { return m_pointed; }
    /// Haptic thread (after read()): where the device is heading.
    [[nodiscard]] const Eigen::Vector3d& target() const noexcept { return m_position.read_slot(); }

private:
    TripleBuffer<Eigen::Vector3d> m_position;
    Eigen::Vector3d m_pointed;
    Eigen::Vector3d m_position_now; ///< the haptic thread's: where the device is
    static constexpr double k_max_step_mm = 1.0;
    Eigen::Quaterniond m_orientation;
    DeviceLimits m_limits;
};

} // namespace vox::haptics
