#include "haptics/coupled_tool.hpp"

#include <algorithm>
#include <chrono>

namespace vox::haptics {

CoupledTool::CoupledTool(const contact::ToolShape& shape, const contact::ContactParameters& contact, const CouplingSettings& coupling,
                         std::size_t snapshot_capacity)
    : m_parameters(contact), m_coupling(coupling), m_mover(shape, contact, snapshot_capacity), m_distance(snapshot_capacity)
{
    m_proxy.shape = &shape;
}

contact::PlacedShape CoupledTool::handed_pose() const
{
    contact::PlacedShape out = m_proxy;
    const double force = m_patch_force.norm();
    if (force > 0.0) out.position += m_patch.give_mm() / force * m_patch_force;
    return out;
}

void CoupledTool::measure_contact(const contact::SurfacePoints& surface, double dt_s) noexcept
{
    // The points' distances at the proxy, measured once: the contact and the continuous check
    // both need them.
    const std::span<double> distance(m_distance.data(), std::min(surface.count, m_distance.size()));
    m_contact = contact::penalty_totals(m_proxy, m_parameters, surface, false, distance);
    m_patch_us = 0.0;
    m_patch_force = Eigen::Vector3d::Zero();
    if (surface.patch.free == 0) return;
    // The patch stands in for the snapshot's points at the contact.
    const auto start = std::chrono::steady_clock::now();
    const contact::ContactTotals patch = m_patch.step(m_proxy, m_parameters, surface, dt_s);
    m_patch_us = std::chrono::duration<double, std::micro>(std::chrono::steady_clock::now() - start).count();
    m_patch_force = patch.force_on_tool_n;
    m_contact.force_on_tool_n += patch.force_on_tool_n;
    m_contact.torque_on_tool_n_mm += patch.torque_on_tool_n_mm;
    m_contact.stiffness_n_per_mm += patch.stiffness_n_per_mm;
    m_contact.area_mm2 += patch.area_mm2;
    m_contact.inner_reaches_surface = m_contact.inner_reaches_surface || patch.inner_reaches_surface;
}

void CoupledTool::prepare(const DeviceState& device, const contact::SurfacePoints& surface, double dt_s) noexcept
{
    if (!m_started) return;
    m_proxy.orientation = device.orientation;
    measure_contact(surface, dt_s);
    m_prepared_on = &surface;
    m_prepared_t_s = surface.t_s;
}

Eigen::Vector3d CoupledTool::update(const DeviceState& device, const contact::SurfacePoints& surface, double dt_s) noexcept
{
    if (!m_started) {
        m_proxy.position = m_previous_felt = m_previous_device = device.position_mm;
        m_snapshot_t_s = surface.t_s;
        m_started = true;
    }
    const bool fresh = surface.t_s != m_snapshot_t_s;
    if (fresh) {
        m_spread_ticks = std::clamp(m_ticks_on_snapshot, 1, k_max_spread_ticks);
        m_ticks_on_snapshot = 0;
        m_snapshot_t_s = surface.t_s;
    }
    ++m_ticks_on_snapshot;
    const Eigen::Vector3d felt_before = felt_position();
    // The contact at the proxy: prepared after the last tick on this very snapshot, or measured now.
    m_used_prepared = m_prepared_on == &surface && m_prepared_t_s == surface.t_s;
    if (!m_used_prepared) {
        m_proxy.orientation = device.orientation;
        measure_contact(surface, dt_s);
    }
    m_prepared_on = nullptr;
    const std::span<const double> distance(m_distance.data(), std::min(surface.count, m_distance.size()));
    const double kc = m_coupling.stiffness_n_per_mm;
    const bool passing = m_passing.load(std::memory_order_relaxed);
    if (passing) {
        m_proxy.position = device.position_mm; // the material gives way: the simulation cuts it
    } else {
        // One Newton step a tick on k_c (x_d - x) + F(x) = 0, F linearised at the proxy, held
        // within the depth bound (contact/proxy.hpp): warm started from the last tick, the proxy
        // converges within a few ticks of any change (a millisecond moves the device a few
        // micrometres).
        m_mover.step(m_proxy, device.position_mm, kc, m_contact, surface, distance);
    }
    // The tick a new snapshot arrives, the proxy's move (the surface moved under it) is not felt
    // yet: the felt proxy moves with the device that tick, and the rest of the move is spread
    // evenly over as many ticks as the last snapshot lasted. The spread of the snapshot before, if
    // unfinished, goes on within it.
    if (fresh) {
        m_spread = felt_before + (device.position_mm - m_previous_device) - m_proxy.position;
        m_spread_step = m_spread / m_spread_ticks;
    } else if (m_spread.squaredNorm() > 0.0) {
        m_spread = m_spread.squaredNorm() > m_spread_step.squaredNorm() ? Eigen::Vector3d(m_spread - m_spread_step) : Eigen::Vector3d::Zero();
    }
    const Eigen::Vector3d felt = felt_position();
    const double dt = dt_s > 0.0 ? dt_s : 1e-3;
    const Eigen::Vector3d relative_velocity = ((felt - m_previous_felt) - (device.position_mm - m_previous_device)) / dt; // mm/s
    m_previous_felt = felt;
    m_previous_device = device.position_mm;
    if (passing) { // cutting through: the contact where the tool is, as the simulation presses it
        m_spread.setZero();
        return m_contact.force_on_tool_n;
    }
    return kc * (felt - device.position_mm) + m_coupling.damping_n_s_per_mm * relative_velocity;
}

} // namespace vox::haptics
