#pragma once
// A 6-DoF controller of the SpaceMouse class as a live device: its input reports read through
// hidapi without waiting, the cap's displacement driving the tool's velocity (rate control, as
// such controllers are used: push the cap and the tool moves while it is pushed), position and
// orientation integrated at each read. No force output.

#include "haptics/device.hpp"
#include "haptics/spacemouse_report.hpp"

#include <array>
#include <string>

namespace vox::haptics {

struct SixDofRates {
    double mm_per_s = 60.0;  ///< tool speed at full deflection
    double deg_per_s = 90.0; ///< turning speed at full deflection
};

/// One step of rate control: moves `position` by axes[0..2] * rate * dt (world axes) and turns
/// `orientation` by axes[3..5] * rate * dt about the world axes.
void integrate_six_dof(const std::array<double, 6>& axes, double dt_s, const SixDofRates& rates, Eigen::Vector3d& position,
                       Eigen::Quaterniond& orientation) noexcept;

class SpaceMouseDevice final : public Device {
public:
    /// Opens the HID device at `path` (from enumerate_hid_devices); throws InputError naming it
    /// when it cannot be opened (the udev rule of udev_rule_advice() is usually missing).
    SpaceMouseDevice(const std::string& path, const std::string& product, const Eigen::Vector3d& start_mm,
                     const Eigen::Quaterniond& orientation, const SixDofRates& rates = {}, const AxisMapping& mapping = {});
    ~SpaceMouseDevice() override;
    SpaceMouseDevice(const SpaceMouseDevice&) = delete;
    SpaceMouseDevice& operator=(const SpaceMouseDevice&) = delete;

    [[nodiscard]] std::string name() const override { return m_name; }
    [[nodiscard]] const DeviceLimits& limits() const override { return m_limits; }
    bool read(double t_s, DeviceState& state) noexcept override;

private:
    void* m_handle = nullptr; ///< hid_device
    std::string m_name;
    SixDofRates m_rates;
    AxisMapping m_mapping;
    SixAxisState m_raw;
    DeviceLimits m_limits;
    Eigen::Vector3d m_position;
    Eigen::Quaterniond m_orientation;
    double m_last_t = -1.0;
    bool m_failed = false; ///< a read failed: the device is gone
};

} // namespace vox::haptics
