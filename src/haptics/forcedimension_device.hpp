#pragma once
// A Force Dimension device (omega, delta, sigma, lambda; a Novint Falcon through the same SDK)
// through the DHD API, loaded at run time (haptics/vendor_library.hpp): libdhd.so from the
// loader's path or VOX_LIBDHD. Polled by the haptic loop's own 1 kHz thread. The device reports
// metres; the loop works in mm. Forces in N, in the device's own frame.

#include "haptics/device.hpp"
#include "haptics/forcedimension_abi.hpp"
#include "haptics/vendor_library.hpp"

#include <atomic>
#include <chrono>
#include <string>
#include <vector>

namespace vox::haptics {

class ForceDimensionDevice final : public Device {
public:
    /// Opens the first device (`index` 0) and enables its force output. Throws InputError naming
    /// the library or the device and the vendor's error string.
    explicit ForceDimensionDevice(int index = 0);
    ~ForceDimensionDevice() override;
    ForceDimensionDevice(const ForceDimensionDevice&) = delete;
    ForceDimensionDevice& operator=(const ForceDimensionDevice&) = delete;

    [[nodiscard]] std::string name() const override { return "Force Dimension " + m_info.model; }
    [[nodiscard]] const DeviceLimits& limits() const override { return m_limits; }
    [[nodiscard]] const ForceDeviceInfo& info() const { return m_info; }
    bool read(double t_s, DeviceState& state) noexcept override;
    void send(const Eigen::Vector3d& force_n, const Eigen::Vector3d& torque_nm) noexcept override;
    [[nodiscard]] const char* fault() const noexcept override { return m_fault.load(std::memory_order_relaxed); }
    /// A device faulted for half a second (unplugged, switched off) is closed and opened again,
    /// every half second until it answers; the loop makes no DHD call meanwhile.
    void recover() override;

    /// Every device the library finds, or one entry saying why there is none.
    static std::vector<ForceDeviceInfo> probe();

private:
    /// The last error's text, never null.
    [[nodiscard]] const char* last_error() const noexcept;

    VendorLibrary m_library;
    struct Api {
        dhd::GetDeviceCount get_device_count;
        dhd::OpenID open_id;
        dhd::Close close;
        dhd::GetSystemName get_system_name;
        dhd::GetSerialNumber get_serial_number; ///< optional
        dhd::GetPosition get_position;
        dhd::GetOrientationFrame get_orientation_frame;
        dhd::GetButtonMask get_button_mask;
        dhd::SetForce set_force;
        dhd::SetForceAndTorque set_force_and_torque; ///< optional: used when present
        dhd::EnableForce enable_force;
        dhd::GetMaxForce get_max_force;
        dhd::ErrorGetLast error_get_last;
        dhd::ErrorGetLastStr error_get_last_str; ///< optional
        dhd::ErrorGetStr error_get_str;          ///< optional
    } m_api;
    /// Who may call the DHD API for the device: the loop (ok, or faulted and still polling),
    /// or, once the loop has stood off, recover() reopening it. The loop's acquire of ok makes
    /// the id recover() wrote visible.
    enum Link : int { ok, faulted, stand_off_asked, standing_off };
    std::atomic<int> m_link{ok};
    std::chrono::steady_clock::time_point m_fault_since, m_next_try; ///< recover()'s own
    int m_index = 0;
    char m_id = dhd::k_default_device;
    ForceDeviceInfo m_info;
    DeviceLimits m_limits;
    std::atomic<const char*> m_fault{nullptr};
};

} // namespace vox::haptics
