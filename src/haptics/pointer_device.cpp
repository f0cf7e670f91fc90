#include "haptics/pointer_device.hpp"

namespace vox::haptics {

PointerDevice::PointerDevice(const Eigen::Vector3d& start_mm, const Eigen::Quaterniond& orientation)
    : m_position(start_mm), m_pointed(start_mm), m_position_now(start_mm), m_orientation(orientation.normalized())
{
}

bool PointerDevice::read(double t_s, DeviceState& state) noexcept
{
    m_position.update();
    const Eigen::Vector3d step = m_position.read_slot() - m_position_now;
    const double length = step.norm();
    m_position_now += length > k_max_step_mm ? Eigen::Vector3d(step * (k_max_step_mm / length)) : step;
    state.t_s = t_s;
    state.position_mm = m_position_now;
    state.orientation = m_orientation;
    state.buttons = 0;
    return true;
}

void PointerDevice::point_at(const Eigen::Vector3d& position_mm) noexcept
{
    if (!position_mm.allFinite()) return;
    m_pointed = position_mm;
    m_position.write_slot() = position_mm;
    m_position.publish();
}

} // namespace vox::haptics
