#include "haptics/virtual_device.hpp"

#include "core/error.hpp"

#include <cmath>

namespace vox::haptics {

VirtualDevice::VirtualDevice(std::vector<KeyFrame> frames) : m_frames(std::move(frames))
{
    if (m_frames.empty()) throw InputError("virtual device: no key frames");
    for (std::size_t i = 0; i < m_frames.size(); ++i) {
        if (!std::isfinite(m_frames[i].t_s) || !m_frames[i].position_mm.allFinite())
            throw InputError("virtual device: key frame " + std::to_string(i) + " is not finite");
        if (i && m_frames[i].t_s < m_frames[i - 1].t_s)
            throw InputError("virtual device: key frame " + std::to_string(i) + " goes back in time");
        m_frames[i].orientation.normalize();
    }
    m_limits.workspace_min_mm = m_frames.front().position_mm;
    m_limits.workspace_max_mm = m_frames.front().position_mm;
    for (const KeyFrame& f : m_frames) {
        m_limits.workspace_min_mm = m_limits.workspace_min_mm.cwiseMin(f.position_mm);
        m_limits.workspace_max_mm = m_limits.workspace_max_mm.cwiseMax(f.position_mm);
    }
}

bool VirtualDevice::read(double t_s, DeviceState& state) noexcept
{
    state.t_s = t_s;
    state.buttons = 0;
    if (!(t_s > m_frames.front().t_s)) {
        state.position_mm = m_frames.front().position_mm;
        state.orientation = m_frames.front().orientation;
        return true;
    }
    if (t_s >= m_frames.back().t_s) {
        state.position_mm = m_frames.back().position_mm;
        state.orientation = m_frames.back().orientation;
        return true;
    }
    if (m_cursor >= m_frames.size() || m_frames[m_cursor].t_s > t_s) m_cursor = 0;
    while (m_cursor + 1 < m_frames.size() && m_frames[m_cursor + 1].t_s <= t_s) ++m_cursor;
    const KeyFrame& a = m_frames[m_cursor];
    const KeyFrame& b = m_frames[m_cursor + 1];
    const double span = b.t_s - a.t_s;
    const double s = span > 0.0 ? (t_s - a.t_s) / span : 1.0;
    state.position_mm = (1.0 - s) * a.position_mm + s * b.position_mm;
    state.orientation = a.orientation.slerp(s, b.orientation);
    return true;
}

} // namespace vox::haptics
