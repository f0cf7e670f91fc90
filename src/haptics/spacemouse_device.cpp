#include "haptics/spacemouse_device.hpp"

#include "core/error.hpp"

#include <hidapi.h>

#include <algorithm>
#include <cmath>

namespace vox::haptics {

void integrate_six_dof(const std::array<double, 6>& axes, double dt_s, const SixDofRates& rates, Eigen::Vector3d& position,
                       Eigen::Quaterniond& orientation) noexcept
{
    position += rates.mm_per_s * dt_s * Eigen::Vector3d(axes[0], axes[1], axes[2]);
    const Eigen::Vector3d turn = rates.deg_per_s * M_PI / 180.0 * dt_s * Eigen::Vector3d(axes[3], axes[4], axes[5]);
    const double angle = turn.norm();
    if (angle > 0.0) orientation = (Eigen::Quaterniond(Eigen::AngleAxisd(angle, turn / angle)) * orientation).normalized();
}

SpaceMouseDevice::SpaceMouseDevice(const std::string& path, const std::string& product, const Eigen::Vector3d& start_mm,
                                   const Eigen::Quaterniond& orientation, const SixDofRates& rates, const AxisMapping& mapping)
    : m_name(product.empty() ? "6-DoF controller (" + path + ")" : product), m_rates(rates), m_mapping(mapping), m_position(start_mm),
      m_orientation(orientation.normalized())
{
    m_handle = hid_open_path(path.c_str());
    if (!m_handle) throw InputError(path + ": cannot open this 6-DoF controller (no permission? see `voxsculpt devices`)");
    hid_set_nonblocking(static_cast<hid_device*>(m_handle), 1);
}

SpaceMouseDevice::~SpaceMouseDevice()
{
    if (m_handle) hid_close(static_cast<hid_device*>(m_handle));
}

bool SpaceMouseDevice::read(double t_s, DeviceState& state) noexcept
{
    // Drain what has arrived since the last tick (reports come at about 60-120 Hz), never waiting.
    // A failed read (the controller unplugged) stops the tool where it is: the last deflection must
    // not keep moving it, and hidapi is not asked again (its error path allocates).
    std::uint8_t report[64];
    for (int n = 0; n < 16 && !m_failed; ++n) {
        const int got = hid_read_timeout(static_cast<hid_device*>(m_handle), report, sizeof report, 0);
        if (got < 0) {
            m_failed = true;
            m_raw = {};
        }
        if (got <= 0) break;
        parse_spacemouse_report(std::span<const std::uint8_t>(report, static_cast<std::size_t>(got)), m_raw);
    }
    const double dt = m_last_t < 0.0 ? 0.0 : std::clamp(t_s - m_last_t, 0.0, 0.05);
    m_last_t = t_s;
    integrate_six_dof(map_axes(m_raw, m_mapping), dt, m_rates, m_position, m_orientation);
    state.t_s = t_s;
    state.position_mm = m_position;
    state.orientation = m_orientation;
    state.buttons = m_raw.buttons;
    return true;
}

} // namespace vox::haptics
