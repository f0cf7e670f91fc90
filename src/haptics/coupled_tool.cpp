#include "haptics/coupled_tool.hpp"

namespace vox::haptics {

CoupledTool::CoupledTool(const contact::ToolShape& shape, const contact::ContactParameters& contact, const CouplingSettings& coupling)
    : m_parameters(contact), m_coupling(coupling)
{
    m_proxy.shape = &shape;
}

Eigen::Vector3d CoupledTool::update(const DeviceState& device, const contact::SurfacePoints& surface, double dt_s) noexcept
{
    if (!m_started) {
        m_proxy.position = m_previous_proxy = m_previous_device = device.position_mm;
        m_started = true;
    }
    m_proxy.orientation = device.orientation;
    const double kc = m_coupling.stiffness_n_per_mm;
    // One Newton step a tick on k_c (x_d - x) + F(x) = 0, F linearised at the proxy: warm started
    // from the last tick, the proxy converges within a few ticks of any change (a millisecond
    // moves the device a few micrometres).
    m_contact = contact::penalty_totals(m_proxy, m_parameters, surface, false);
    const Eigen::Matrix3d a = kc * Eigen::Matrix3d::Identity() + m_contact.stiffness_n_per_mm;
    const Eigen::Vector3d residual = kc * (device.position_mm - m_proxy.position) + m_contact.force_on_tool_n;
    const Eigen::Vector3d step = a.ldlt().solve(residual);
    if (step.allFinite()) m_proxy.position += step;
    const double dt = dt_s > 0.0 ? dt_s : 1e-3;
    const Eigen::Vector3d relative_velocity =
        ((m_proxy.position - m_previous_proxy) - (device.position_mm - m_previous_device)) / dt; // mm/s
    m_previous_proxy = m_proxy.position;
    m_previous_device = device.position_mm;
    return kc * (m_proxy.position - device.position_mm) + m_coupling.damping_n_s_per_mm * relative_velocity;
}

} // namespace vox::haptics
