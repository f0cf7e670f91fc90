#pragma once
// A device seen in the scene's frame, with a clutch. An absolute device (a Touch, an omega)
// reports its pose in its own frame, about its own centre; the scene puts that frame somewhere:
// scene = origin + scale x rotation x device. While the clutch button is held the hand moves
// without moving the tool (indexing, as with a mouse lifted off its pad): the tool stays where it
// was and no force is sent; when the button is let go the frame has moved so that the tool goes
// on from where it stayed, at the hand's new place and turn. Forces go back turned into the
// device's frame, not scaled (a 2:1 scale still renders the contact's newtons).

#include "haptics/device.hpp"

#include <memory>

namespace vox::haptics {

struct DeviceFrame {
    Eigen::Vector3d origin_mm = Eigen::Vector3d::Zero();
    Eigen::Quaterniond rotation = Eigen::Quaterniond::Identity();
    double scale = 1.0; ///< scene mm per device mm
};

class FramedDevice final : public Device {
public:
    /// `clutch_mask`: the buttons that clutch (default the first; 0: none). `inner` must outlive this.
    FramedDevice(Device& inner, const DeviceFrame& frame, std::uint32_t clutch_mask = 1u);
    /// The same, owning `inner`.
    FramedDevice(std::unique_ptr<Device> inner, const DeviceFrame& frame, std::uint32_t clutch_mask = 1u);

    [[nodiscard]] std::string name() const override { return m_inner.name(); }
    [[nodiscard]] const DeviceLimits& limits() const override { return m_inner.limits(); }
    bool read(double t_s, DeviceState& state) noexcept override;
    void send(const Eigen::Vector3d& force_n, const Eigen::Vector3d& torque_nm) noexcept override;
    [[nodiscard]] const char* fault() const noexcept override { return m_inner.fault(); }
    void recover() override { m_inner.recover(); }
    bool run_servo(ServoTick tick, void* user) override { return m_inner.run_servo(tick, user); }
    void stop_servo() override { m_inner.stop_servo(); }

    /// Whether the clutch is held (at the last read).
    [[nodiscard]] bool clutched() const noexcept { return m_clutched; }
    /// The frame now (its origin and turn move with each indexing).
    [[nodiscard]] const DeviceFrame& frame() const noexcept { return m_frame; }

private:
    /// A point of the device's frame in the scene's.
    [[nodiscard]] Eigen::Vector3d to_scene(const Eigen::Vector3d& device_mm) const noexcept;

    std::unique_ptr<Device> m_owned; ///< the inner device, when this one owns it
    Device& m_inner;
    DeviceFrame m_frame;
    std::uint32_t m_clutch_mask;
    Eigen::Quaterniond m_turn = Eigen::Quaterniond::Identity(); ///< the tool's turn relative to the hand's, from indexing
    bool m_clutched = false;
    bool m_started = false; ///< a reading came through
    DeviceState m_held; ///< the tool's pose while clutched
};

} // namespace vox::haptics
