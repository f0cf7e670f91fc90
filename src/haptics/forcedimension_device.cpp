#include "haptics/forcedimension_device.hpp"

#include "core/error.hpp"

#include <vector>

namespace vox::haptics {

ForceDimensionDevice::ForceDimensionDevice(int index) : m_library("libdhd.so", "VOX_LIBDHD")
{
    const VendorLibrary& l = m_library;
    m_api = {l.required<dhd::GetDeviceCount>("dhdGetDeviceCount"),
             l.required<dhd::OpenID>("dhdOpenID"),
             l.required<dhd::Close>("dhdClose"),
             l.required<dhd::GetSystemName>("dhdGetSystemName"),
             l.optional<dhd::GetSerialNumber>("dhdGetSerialNumber"),
             l.required<dhd::GetPosition>("dhdGetPosition"),
             l.required<dhd::GetOrientationFrame>("dhdGetOrientationFrame"),
             l.required<dhd::GetButtonMask>("dhdGetButtonMask"),
             l.required<dhd::SetForce>("dhdSetForce"),
             l.optional<dhd::SetForceAndTorque>("dhdSetForceAndTorque"),
             l.required<dhd::EnableForce>("dhdEnableForce"),
             l.required<dhd::GetMaxForce>("dhdGetMaxForce"),
             l.required<dhd::ErrorGetLast>("dhdErrorGetLast"),
             l.optional<dhd::ErrorGetLastStr>("dhdErrorGetLastStr"),
             l.optional<dhd::ErrorGetStr>("dhdErrorGetStr")};
    const std::string who = "Force Dimension device (" + m_library.name() + ")";
    const int count = m_api.get_device_count();
    if (count < 0) throw InputError(who + ": cannot count the devices: " + last_error());
    if (count == 0) throw InputError(who + ": no device (is it plugged in and powered, and may this user open it?)");
    if (index >= count) throw InputError(who + ": device " + std::to_string(index) + " asked for, " + std::to_string(count) + " found");
    m_index = index;
    const int id = m_api.open_id(static_cast<char>(index));
    if (id < 0) throw InputError(who + ": cannot open device " + std::to_string(index) + ": " + last_error());
    m_id = static_cast<char>(id);
    const char* model = m_api.get_system_name(m_id);
    m_info.model = model && *model ? model : "device";
    unsigned short serial = 0;
    if (m_api.get_serial_number && m_api.get_serial_number(&serial, m_id) >= 0) m_info.serial = std::to_string(serial);
    m_info.max_force_n = m_api.get_max_force(m_id);
    m_limits.force_output = true;
    m_limits.max_force_n = m_info.max_force_n > 0.0 ? m_info.max_force_n : 3.0;
    if (m_api.enable_force(1, m_id) < 0) {
        const std::string why = last_error();
        m_api.close(m_id);
        throw InputError(who + ": cannot enable the force of " + m_info.model + ": " + why);
    }
}

ForceDimensionDevice::~ForceDimensionDevice()
{
    m_api.set_force(0.0, 0.0, 0.0, m_id);
    m_api.enable_force(0, m_id);
    m_api.close(m_id);
}

const char* ForceDimensionDevice::last_error() const noexcept
{
    const char* s = m_api.error_get_last_str ? m_api.error_get_last_str() : nullptr;
    if (!s && m_api.error_get_str) s = m_api.error_get_str(m_api.error_get_last());
    return s && *s ? s : "the device reported an error";
}

bool ForceDimensionDevice::read(double t_s, DeviceState& state) noexcept
{
    const int link = m_link.load(std::memory_order_acquire);
    if (link == stand_off_asked) { // recover() is to reopen the device: no call from here until it has
        m_link.store(standing_off, std::memory_order_release);
        return false;
    }
    if (link == standing_off) return false;
    double x = 0.0, y = 0.0, z = 0.0, r[3][3] = {};
    // Returns below 0 are errors (1 is the SDK's time guard: a valid reading).
    if (m_api.get_position(&x, &y, &z, m_id) < 0 || m_api.get_orientation_frame(r, m_id) < 0) {
        m_fault.store(last_error(), std::memory_order_relaxed);
        int expected = ok;
        m_link.compare_exchange_strong(expected, faulted, std::memory_order_acq_rel);
        return false;
    }
    m_fault.store(nullptr, std::memory_order_relaxed);
    int expected = faulted;
    m_link.compare_exchange_strong(expected, ok, std::memory_order_acq_rel); // it came back by itself
    state.t_s = t_s;
    state.position_mm = 1e3 * Eigen::Vector3d(x, y, z);
    Eigen::Matrix3d m;
    m << r[0][0], r[0][1], r[0][2], r[1][0], r[1][1], r[1][2], r[2][0], r[2][1], r[2][2];
    state.orientation = Eigen::Quaterniond(m).normalized();
    state.buttons = m_api.get_button_mask(m_id);
    return true;
}

void ForceDimensionDevice::send(const Eigen::Vector3d& force_n, const Eigen::Vector3d& torque_nm) noexcept
{
    const int link = m_link.load(std::memory_order_acquire);
    if (link != ok && link != faulted) return; // standing off for recover()
    const bool faulted = m_fault.load(std::memory_order_relaxed) != nullptr;
    const Eigen::Vector3d f = faulted ? Eigen::Vector3d::Zero() : force_n;
    const Eigen::Vector3d t = faulted ? Eigen::Vector3d::Zero() : torque_nm;
    const int result = m_api.set_force_and_torque ? m_api.set_force_and_torque(f.x(), f.y(), f.z(), t.x(), t.y(), t.z(), m_id)
                                                  : m_api.set_force(f.x(), f.y(), f.z(), m_id);
    if (result < 0) {
        m_fault.store(last_error(), std::memory_order_relaxed);
        int expected = ok;
        m_link.compare_exchange_strong(expected, faulted, std::memory_order_acq_rel);
    }
}

void ForceDimensionDevice::recover()
{
    using namespace std::chrono_literals;
    const auto now = std::chrono::steady_clock::now();
    int link = m_link.load(std::memory_order_acquire);
    if (link == ok) {
        m_fault_since = {};
        return;
    }
    if (link == faulted) { // a moment's error passes by itself; one that lasts needs the device reopened
        if (m_fault_since == std::chrono::steady_clock::time_point{}) m_fault_since = now;
        if (now - m_fault_since >= 500ms) m_link.compare_exchange_strong(link, stand_off_asked, std::memory_order_acq_rel);
        return;
    }
    if (link != standing_off || now < m_next_try) return;
    m_next_try = now + 500ms;
    m_api.close(m_id);
    const int id = m_api.open_id(static_cast<char>(m_index));
    if (id < 0) {
        m_fault.store(last_error(), std::memory_order_relaxed);
        return;
    }
    if (m_api.enable_force(1, static_cast<char>(id)) < 0) {
        m_fault.store(last_error(), std::memory_order_relaxed);
        m_api.close(static_cast<char>(id));
        return;
    }
    m_id = static_cast<char>(id);
    m_fault_since = {};
    m_link.store(ok, std::memory_order_release); // the fault clears at the loop's next good reading
}

std::vector<ForceDeviceInfo> ForceDimensionDevice::probe()
{
    std::vector<ForceDeviceInfo> out;
    try {
        for (int i = 0;; ++i) {
            const ForceDimensionDevice d(i);
            out.push_back(d.info());
        }
    } catch (const InputError& e) {
        // The first failure past the devices found is "device N asked for, N found": not a problem.
        if (out.empty()) out.push_back({"", "", 0.0, e.what()});
    }
    return out;
}

} // namespace vox::haptics
