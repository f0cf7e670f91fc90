#include "haptics/framed_device.hpp"

#include <utility>

namespace vox::haptics {

FramedDevice::FramedDevice(Device& inner, const DeviceFrame& frame, std::uint32_t clutch_mask)
    : m_inner(inner), m_frame(frame), m_clutch_mask(clutch_mask)
{
    m_frame.rotation.normalize();
}

FramedDevice::FramedDevice(std::unique_ptr<Device> inner, const DeviceFrame& frame, std::uint32_t clutch_mask)
    : m_owned(std::move(inner)), m_inner(*m_owned), m_frame(frame), m_clutch_mask(clutch_mask)
{
    m_frame.rotation.normalize();
}

Eigen::Vector3d FramedDevice::to_scene(const Eigen::Vector3d& device_mm) const noexcept
{
    return m_frame.origin_mm + m_frame.scale * (m_frame.rotation * device_mm);
}

bool FramedDevice::read(double t_s, DeviceState& state) noexcept
{
    DeviceState hand = state; // where the inner device leaves it on a failed read
    if (!m_inner.read(t_s, hand)) return false;
    const bool clutch = (hand.buttons & m_clutch_mask) != 0;
    const Eigen::Quaterniond hand_turn = m_frame.rotation * hand.orientation;
    if (clutch && !m_clutched) { // the tool stays where the last reading put it (the first: where this one would)
        m_held = state;
        if (!m_started) {
            m_held.position_mm = to_scene(hand.position_mm);
            m_held.orientation = hand_turn;
        }
    }
    m_started = true;
    if (!clutch && m_clutched) {
        // Let go: the frame moves so that the hand, where it is now, holds the tool where it stayed.
        m_frame.origin_mm = m_held.position_mm - m_frame.scale * (m_frame.rotation * hand.position_mm);
        m_turn = m_held.orientation * hand_turn.conjugate();
    }
    m_clutched = clutch;
    state.t_s = t_s;
    state.buttons = hand.buttons;
    if (clutch) {
        state.position_mm = m_held.position_mm;
        state.orientation = m_held.orientation;
        return true;
    }
    state.position_mm = to_scene(hand.position_mm);
    state.orientation = (m_turn * hand_turn).normalized();
    return true;
}

void FramedDevice::send(const Eigen::Vector3d& force_n, const Eigen::Vector3d& torque_nm) noexcept
{
    if (m_clutched) {
        m_inner.send(Eigen::Vector3d::Zero(), Eigen::Vector3d::Zero());
        return;
    }
    const Eigen::Quaterniond back = m_frame.rotation.conjugate();
    m_inner.send(back * force_n, back * torque_nm);
}

} // namespace vox::haptics
