#pragma once
// A 3D Systems device (Touch, Touch X, Phantom Premium...) through the OpenHaptics HD API,
// loaded at run time (haptics/vendor_library.hpp): libHD.so from the loader's path or VOX_LIBHD.
// The HD scheduler's 1 kHz callback is the haptic loop's tick (run_servo); reads and sends are
// valid only inside it, each tick one hdBeginFrame ... hdEndFrame. Positions in mm, forces in N,
// in the device's own frame.

#include "haptics/device.hpp"
#include "haptics/openhaptics_abi.hpp"
#include "haptics/vendor_library.hpp"

#include <atomic>
#include <string>

namespace vox::haptics {

class OpenHapticsDevice final : public Device {
public:
    /// Opens the default device, checks its calibration (updating it where the device can do so
    /// itself) and enables force output. Throws InputError naming the library or the device and
    /// the vendor's error string.
    OpenHapticsDevice();
    ~OpenHapticsDevice() override;
    OpenHapticsDevice(const OpenHapticsDevice&) = delete;
    OpenHapticsDevice& operator=(const OpenHapticsDevice&) = delete;

    [[nodiscard]] std::string name() const override { return "OpenHaptics " + m_info.model; }
    [[nodiscard]] const DeviceLimits& limits() const override { return m_limits; }
    [[nodiscard]] const ForceDeviceInfo& info() const { return m_info; }
    bool read(double t_s, DeviceState& state) noexcept override;
    void send(const Eigen::Vector3d& force_n, const Eigen::Vector3d& torque_nm) noexcept override;
    [[nodiscard]] const char* fault() const noexcept override { return m_fault.load(std::memory_order_relaxed); }
    bool run_servo(ServoTick tick, void* user) override;
    void stop_servo() override;

    /// The device the library finds, or why there is none (no library, no device, its error).
    static ForceDeviceInfo probe();

private:
    static hd::HDCallbackCode servo(void* self) noexcept;
    /// The pending error's text (hdGetErrorString when the library has it), "" when none.
    [[nodiscard]] const char* error_text(const hd::HDErrorInfo& e) const noexcept;

    VendorLibrary m_library;
    struct Api {
        hd::InitDevice init_device;
        hd::DisableDevice disable_device; ///< optional
        hd::BeginFrame begin_frame;
        hd::EndFrame end_frame;
        hd::GetDoublev get_doublev;
        hd::GetIntegerv get_integerv;
        hd::SetDoublev set_doublev;
        hd::Enable enable;
        hd::StartScheduler start_scheduler;
        hd::StopScheduler stop_scheduler;
        hd::ScheduleAsynchronous schedule_asynchronous;
        hd::ScheduleSynchronous schedule_synchronous;
        hd::Unschedule unschedule; ///< optional
        hd::GetError get_error;
        hd::GetErrorString get_error_string; ///< optional
        hd::GetString get_string;            ///< optional
        hd::CheckCalibration check_calibration;
        hd::UpdateCalibration update_calibration; ///< optional
    } m_api;
    hd::HHD m_device = hd::HD_INVALID_HANDLE;
    ForceDeviceInfo m_info;
    DeviceLimits m_limits;
    bool m_in_frame = false; ///< read() began a frame that send() ends
    std::atomic<const char*> m_fault{nullptr};
    ServoTick m_tick = nullptr;
    void* m_tick_user = nullptr;
    hd::HDSchedulerHandle m_callback = 0;
    bool m_scheduled = false;
    std::atomic<bool> m_stopping{false}, m_in_tick{false};
};

} // namespace vox::haptics
