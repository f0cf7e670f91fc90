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

class Device {
public:
    virtual ~Device() = default;
    [[nodiscard]] virtual std::string name() const = 0;
    [[nodiscard]] virtual const DeviceLimits& limits() const = 0;
    /// The device's state at loop time t_s; false when it has nothing new (state is left as is).
    virtual bool read(double t_s, DeviceState& state) noexcept = 0;
    /// Force (N) and torque (N m) to render; ignored by devices without force output.
    virtual void send(const Eigen::Vector3d& /*force_n*/, const Eigen::Vector3d& /*torque_nm*/) noexcept {}
};

} // namespace vox::haptics
