#pragma once
// A device that follows key frames (the scene script, or a pose file): position interpolated
// linearly, orientation by slerp, held before the first and after the last key frame. No force
// output. Headless runs drive their tools with it.

#include "haptics/device.hpp"

#include <vector>

namespace vox::haptics {

struct KeyFrame {
    double t_s = 0.0;
    Eigen::Vector3d position_mm = Eigen::Vector3d::Zero();
    Eigen::Quaterniond orientation = Eigen::Quaterniond::Identity();
};

class VirtualDevice final : public Device {
public:
    /// Key frames in time order (throws InputError otherwise, or when there are none).
    explicit VirtualDevice(std::vector<KeyFrame> frames);
    [[nodiscard]] std::string name() const override { return "virtual (scripted)"; }
    [[nodiscard]] const DeviceLimits& limits() const override { return m_limits; }
    bool read(double t_s, DeviceState& state) noexcept override;

private:
    std::vector<KeyFrame> m_frames;
    DeviceLimits m_limits;
    std::size_t m_cursor = 0; ///< search hint: time mostly moves forward
};

} // namespace vox::haptics
