#pragma once
// One interface for every input device: pose (position, orientation), buttons and time in; force
// (and torque where the device has it) out; its limits declared. A device without force output
// still drives the tool (it ignores send()). read() and send() run in the 1 kHz loop: they must not
// allocate, lock, log or throw.

#include <Eigen/Core>
#include <Eigen/Geometry>

#include <cstdint>
#include <string>

namespace vox::haptics {

struct DeviceState {
    double t_s = 0.0;                                             ///< loop time of the reading
    Eigen::Vector3d position_mm = Eigen::Vector3d::Zero();        ///< tool position, world mm
    Eigen::Quaterniond orientation = Eigen::Quaterniond::Identity();
    std::uint32_t buttons = 0;
};

struct DeviceLimits {
    bool force_output = false;
    bool torque_output = false;
    double max_force_n = 0.0;              ///< what send() may ask for (the safety stage clamps to it)
    double max_stiffness_n_per_mm = 0.0;   ///< the stiffest coupling the device renders stably
    Eigen::Vector3d workspace_min_mm = Eigen::Vector3d::Constant(-1e9);
    Eigen::Vector3d workspace_max_mm = Eigen::Vector3d::Constant(1e9);
};

/// What a force-feedback device reports of itself, for `voxsculpt devices`.
struct ForceDeviceInfo {
    std::string model;
    std::string serial;
    double max_force_n = 0.0;
    std::string problem; ///< why no device could be opened ("" when one was)
};

class Device {
public:
    virtual ~Device() = default;
    [[nodiscard]] virtual std::string name() const = 0;
    [[nodiscard]] virtual const DeviceLimits& limits() const = 0;
    /// The device's state at loop time t_s; false when it has nothing new (state is left as is).
    virtual bool read(double t_s, DeviceState& state) noexcept = 0;
    /// Force (N) and torque (N m) to render; ignored by devices without force output.
    virtual void send(const Eigen::Vector3d& /*force_n*/, const Eigen::Vector3d& /*torque_nm*/) noexcept {}
    /// What keeps the device from working now, in the vendor's words (a cable pulled): a static
    /// string, null while it works. The force sent meanwhile is zero and the state is held.
    [[nodiscard]] virtual const char* fault() const noexcept { return nullptr; }
    /// Called outside the 1 kHz loop (by the simulation thread, once a frame) while fault() is
    /// set: a device that needs it is closed and opened again (a cable plugged back in), without
    /// the loop ever waiting for it. Nothing for devices that come back by themselves.
    virtual void recover() {}

    /// A tick of a servo loop the device's vendor runs itself (OpenHaptics' scheduler).
    using ServoTick = void (*)(void* user) noexcept;
    /// Devices whose vendor runs the 1 kHz servo thread call `tick(user)` from it once a
    /// millisecond (reads and sends are valid only there) and return true; the haptic loop then
    /// starts no thread of its own. False (the default): the loop's own thread polls the device.
    virtual bool run_servo(ServoTick /*tick*/, void* /*user*/) { return false; }
    /// Stops what run_servo() started; no tick runs after it returns.
    virtual void stop_servo() {}
};

} // namespace vox::haptics
