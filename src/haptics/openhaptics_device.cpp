#include "haptics/openhaptics_device.hpp"

#include "core/error.hpp"

#include <cstdio>
#include <thread>

namespace vox::haptics {

namespace {
std::string hex(unsigned int code)
{
    char buffer[16];
    std::snprintf(buffer, sizeof buffer, "0x%04x", code);
    return buffer;
}
} // namespace

OpenHapticsDevice::OpenHapticsDevice() : m_library("libHD.so", "VOX_LIBHD")
{
    const VendorLibrary& l = m_library;
    m_api = {l.required<hd::InitDevice>("hdInitDevice"),
             l.optional<hd::DisableDevice>("hdDisableDevice"),
             l.required<hd::BeginFrame>("hdBeginFrame"),
             l.required<hd::EndFrame>("hdEndFrame"),
             l.required<hd::GetDoublev>("hdGetDoublev"),
             l.required<hd::GetIntegerv>("hdGetIntegerv"),
             l.required<hd::SetDoublev>("hdSetDoublev"),
             l.required<hd::Enable>("hdEnable"),
             l.required<hd::StartScheduler>("hdStartScheduler"),
             l.required<hd::StopScheduler>("hdStopScheduler"),
             l.required<hd::ScheduleAsynchronous>("hdScheduleAsynchronous"),
             l.required<hd::ScheduleSynchronous>("hdScheduleSynchronous"),
             l.optional<hd::Unschedule>("hdUnschedule"),
             l.required<hd::GetError>("hdGetError"),
             l.optional<hd::GetErrorString>("hdGetErrorString"),
             l.optional<hd::GetString>("hdGetString"),
             l.required<hd::CheckCalibration>("hdCheckCalibration"),
             l.optional<hd::UpdateCalibration>("hdUpdateCalibration")};
    auto fail = [&](const std::string& what) {
        const hd::HDErrorInfo e = m_api.get_error();
        std::string why = error_text(e);
        if (why.empty()) why = "error " + hex(static_cast<unsigned>(e.errorCode));
        throw InputError("OpenHaptics device (" + m_library.name() + "): " + what + ": " + why + " (internal error " +
                         std::to_string(e.internalErrorCode) + ")");
    };
    m_device = m_api.init_device(nullptr); // HD_DEFAULT_DEVICE: the one the vendor's set-up names
    if (m_device == hd::HD_INVALID_HANDLE || m_api.get_error().errorCode != static_cast<int>(hd::HD_SUCCESS)) {
        m_device = hd::HD_INVALID_HANDLE;
        fail("cannot open the default device");
    }
    if (m_api.get_string) {
        const char* model = m_api.get_string(hd::HD_DEVICE_MODEL_TYPE);
        const char* serial = m_api.get_string(hd::HD_DEVICE_SERIAL_NUMBER);
        m_info.model = model ? model : "";
        m_info.serial = serial ? serial : "";
    }
    if (m_info.model.empty()) m_info.model = "device";
    m_api.get_doublev(hd::HD_NOMINAL_MAX_FORCE, &m_info.max_force_n);
    m_limits.force_output = true;
    m_limits.max_force_n = m_info.max_force_n > 0.0 ? m_info.max_force_n : 3.0;
    m_api.enable(hd::HD_FORCE_OUTPUT);
    m_api.start_scheduler();
    if (m_api.get_error().errorCode != static_cast<int>(hd::HD_SUCCESS)) fail("cannot start the servo scheduler");
    // Calibration is read inside a frame, on the scheduler's thread.
    struct Check {
        OpenHapticsDevice* self;
        hd::HDenum status;
    } check{this, hd::HD_CALIBRATION_OK};
    auto read_calibration = [](void* user) -> hd::HDCallbackCode {
        auto* c = static_cast<Check*>(user);
        c->self->m_api.begin_frame(c->self->m_device);
        c->status = c->self->m_api.check_calibration();
        c->self->m_api.end_frame(c->self->m_device);
        return hd::HD_CALLBACK_DONE;
    };
    m_api.schedule_synchronous(read_calibration, &check, hd::HD_DEFAULT_SCHEDULER_PRIORITY);
    if (check.status == hd::HD_CALIBRATION_NEEDS_UPDATE && m_api.update_calibration) {
        m_api.update_calibration(hd::HD_CALIBRATION_AUTO);
        m_api.schedule_synchronous(read_calibration, &check, hd::HD_DEFAULT_SCHEDULER_PRIORITY);
    }
    if (check.status != hd::HD_CALIBRATION_OK) {
        m_api.stop_scheduler();
        if (m_api.disable_device) m_api.disable_device(m_device);
        throw InputError("OpenHaptics device " + m_info.model + " (" + m_library.name() +
                         "): not calibrated: put the stylus in its inkwell, or calibrate it with the vendor's diagnostic tool, and start again");
    }
}

OpenHapticsDevice::~OpenHapticsDevice()
{
    stop_servo();
    m_api.stop_scheduler();
    if (m_api.disable_device && m_device != hd::HD_INVALID_HANDLE) m_api.disable_device(m_device);
}

const char* OpenHapticsDevice::error_text(const hd::HDErrorInfo& e) const noexcept
{
    if (e.errorCode == static_cast<int>(hd::HD_SUCCESS)) return "";
    const char* s = m_api.get_error_string ? m_api.get_error_string(static_cast<hd::HDerror>(e.errorCode)) : nullptr;
    return s ? s : "";
}

bool OpenHapticsDevice::read(double t_s, DeviceState& state) noexcept
{
    m_api.begin_frame(m_device);
    m_in_frame = true;
    double transform[16];
    int buttons = 0;
    m_api.get_doublev(hd::HD_CURRENT_TRANSFORM, transform);
    m_api.get_integerv(hd::HD_CURRENT_BUTTONS, &buttons);
    const hd::HDErrorInfo e = m_api.get_error();
    if (e.errorCode != static_cast<int>(hd::HD_SUCCESS)) { // the state is held where it was
        const char* why = error_text(e);
        m_fault.store(*why ? why : "the device reported an error", std::memory_order_relaxed);
        return false;
    }
    m_fault.store(nullptr, std::memory_order_relaxed);
    const Eigen::Map<const Eigen::Matrix4d> m(transform); // column-major, as HD writes it
    state.t_s = t_s;
    state.position_mm = m.block<3, 1>(0, 3);
    state.orientation = Eigen::Quaterniond(Eigen::Matrix3d(m.block<3, 3>(0, 0))).normalized();
    state.buttons = static_cast<std::uint32_t>(buttons);
    return true;
}

void OpenHapticsDevice::send(const Eigen::Vector3d& force_n, const Eigen::Vector3d& /*torque_nm*/) noexcept
{
    if (!m_in_frame) m_api.begin_frame(m_device);
    const bool faulted = m_fault.load(std::memory_order_relaxed) != nullptr;
    const double f[3] = {faulted ? 0.0 : force_n.x(), faulted ? 0.0 : force_n.y(), faulted ? 0.0 : force_n.z()};
    m_api.set_doublev(hd::HD_CURRENT_FORCE, f);
    m_api.end_frame(m_device);
    m_in_frame = false;
}

hd::HDCallbackCode OpenHapticsDevice::servo(void* self) noexcept
{
    auto* d = static_cast<OpenHapticsDevice*>(self);
    // Marked busy before looking at the stop flag, which stop_servo() sets before waiting for
    // the mark to clear (both sequentially consistent): no tick starts after stop_servo() returns.
    d->m_in_tick.store(true);
    const bool go = !d->m_stopping.load();
    if (go) d->m_tick(d->m_tick_user);
    d->m_in_tick.store(false);
    return go ? hd::HD_CALLBACK_CONTINUE : hd::HD_CALLBACK_DONE;
}

bool OpenHapticsDevice::run_servo(ServoTick tick, void* user)
{
    stop_servo();
    m_tick = tick;
    m_tick_user = user;
    m_stopping.store(false);
    m_callback = m_api.schedule_asynchronous(&OpenHapticsDevice::servo, this, hd::HD_MAX_SCHEDULER_PRIORITY);
    m_scheduled = true;
    return true;
}

void OpenHapticsDevice::stop_servo()
{
    if (!m_scheduled) return;
    // The callback ends itself at its next call; a tick running now is waited for.
    m_stopping.store(true);
    if (m_api.unschedule) m_api.unschedule(m_callback);
    while (m_in_tick.load()) std::this_thread::yield();
    m_scheduled = false;
}

ForceDeviceInfo OpenHapticsDevice::probe()
{
    try {
        const OpenHapticsDevice d;
        return d.info();
    } catch (const InputError& e) {
        ForceDeviceInfo none;
        none.problem = e.what();
        return none;
    }
}

} // namespace vox::haptics
