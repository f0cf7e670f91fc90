#include "haptics/coupled_tool.hpp"

#include <algorithm>

namespace vox::haptics {

CoupledTool::CoupledTool(const contact::ToolShape& shape, const contact::ContactParameters& contact, const CouplingSettings& coupling,
                         std::size_t snapshot_capacity)
    : m_parameters(contact), m_coupling(coupling), m_sweep(shape, contact.margin_mm, snapshot_capacity), m_distance(snapshot_capacity)
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
    // The points' distances at the proxy, measured once: the contact and the continuous check
    // below both need them.
    const std::span<double> distance(m_distance.data(), std::min(surface.count, m_distance.size()));
    m_contact = contact::penalty_totals(m_proxy, m_parameters, surface, false, distance);
    const Eigen::Matrix3d a = kc * Eigen::Matrix3d::Identity() + m_contact.stiffness_n_per_mm;
    const Eigen::Vector3d residual = kc * (device.position_mm - m_proxy.position) + m_contact.force_on_tool_n;
    Eigen::Vector3d step = a.ldlt().solve(residual);
    // In contact, the linearised contact holds only over the penetration depths it was taken at:
    // a step longer than the margin could carry a thin tool through the points holding it.
    const double limit = std::max(m_parameters.margin_mm, 0.05);
    if (m_contact.area_mm2 > 0.0 && step.norm() > limit) step *= limit / step.norm();
    if (step.allFinite()) {
        // Continuous collision: a step that would carry the tool past surface points it touches
        // at neither end, or through a face or across an edge between them (a thin blade moving
        // fast), stops where it first touches.
        contact::PlacedShape moved = m_proxy;
        moved.position += step;
        const double t = m_sweep.first_stop(m_proxy, moved, surface, distance);
        m_proxy.position += t * step;
    }
    const double dt = dt_s > 0.0 ? dt_s : 1e-3;
    const Eigen::Vector3d relative_velocity =
        ((m_proxy.position - m_previous_proxy) - (device.position_mm - m_previous_device)) / dt; // mm/s
    m_previous_proxy = m_proxy.position;
    m_previous_device = device.position_mm;
    return kc * (m_proxy.position - device.position_mm) + m_coupling.damping_n_s_per_mm * relative_velocity;
}

} // namespace vox::haptics
