// A stand-in for 3D Systems' libHD.so, built by the tests as their own libHD.so: the HD entry
// points VoxSculpt calls, a 1 kHz scheduler thread, a device that moves along a straight path,
// and a record of the forces it is sent. Set by environment variables read at hdInitDevice:
//   FAKE_HD_NO_DEVICE=1        hdInitDevice fails (no device)
//   FAKE_HD_CALIBRATION=manual the device needs its inkwell (hdCheckCalibration)
//   FAKE_HD_PATH="x y z vx vy vz"  position (mm) at frame 0 and velocity (mm/s) per frame of 1 ms
//   FAKE_HD_FAULT="a b"        frames a .. b-1 report a communication error
//   FAKE_HD_BUTTONS_FROM=n     button 1 held from frame n on
// fake_hd_forces() gives the test the forces set, one per frame.

#include <atomic>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <mutex>
#include <string_view>
#include <thread>

namespace {
struct ErrorInfo {
    int errorCode;
    int internalErrorCode;
    unsigned int hHD;
};
using Callback = unsigned int (*)(void*);

constexpr int k_comm_error = 0x302;
constexpr int k_no_device = 0x301;
constexpr int k_max_frames = 200000;

double g_path[6] = {0, 0, 0, 0, 0, 0};
long g_fault_from = -1, g_fault_to = -1, g_buttons_from = -1;
bool g_manual_calibration = false;
std::atomic<long> g_frame{0};
int g_error = 0;
double g_forces[k_max_frames][3];
std::atomic<long> g_recorded{0};
bool g_force_enabled = false;

std::mutex g_mutex; // guards the callbacks (set up outside the servo thread only)
Callback g_callback = nullptr;
void* g_user = nullptr;
std::atomic<bool> g_running{false};
std::thread g_thread;

long frame_in_fault() { return g_frame >= g_fault_from && g_frame < g_fault_to; }

void servo()
{
    auto deadline = std::chrono::steady_clock::now();
    while (g_running) {
        deadline += std::chrono::milliseconds(1);
        std::this_thread::sleep_until(deadline);
        Callback c = nullptr;
        void* u = nullptr;
        {
            std::lock_guard lock(g_mutex);
            c = g_callback;
            u = g_user;
        }
        if (c && c(u) == 0) {
            std::lock_guard lock(g_mutex);
            if (g_callback == c) g_callback = nullptr;
        }
    }
}
} // namespace

extern "C" {

unsigned int hdInitDevice(const char*)
{
    g_frame = 0;
    g_recorded = 0;
    g_error = 0;
    if (std::getenv("FAKE_HD_NO_DEVICE")) {
        g_error = k_no_device;
        return 0xFFFFFFFF;
    }
    const char* calibration = std::getenv("FAKE_HD_CALIBRATION");
    g_manual_calibration = calibration && std::string_view(calibration) == "manual";
    if (const char* p = std::getenv("FAKE_HD_PATH"))
        std::sscanf(p, "%lf %lf %lf %lf %lf %lf", &g_path[0], &g_path[1], &g_path[2], &g_path[3], &g_path[4], &g_path[5]);
    if (const char* f = std::getenv("FAKE_HD_FAULT")) std::sscanf(f, "%ld %ld", &g_fault_from, &g_fault_to);
    if (const char* b = std::getenv("FAKE_HD_BUTTONS_FROM")) g_buttons_from = std::atol(b);
    return 1;
}
void hdDisableDevice(unsigned int) {}
void hdBeginFrame(unsigned int)
{
    g_error = frame_in_fault() ? k_comm_error : 0;
}
void hdEndFrame(unsigned int) { ++g_frame; }
void hdGetDoublev(unsigned int what, double* out)
{
    const double t = static_cast<double>(g_frame) * 1e-3;
    if (what == 0x2603) { // HD_NOMINAL_MAX_FORCE
        *out = 3.3;
    } else if (what == 0x2050) { // HD_CURRENT_POSITION
        for (int i = 0; i < 3; ++i) out[i] = g_path[i] + g_path[3 + i] * t;
    } else if (what == 0x2052) { // HD_CURRENT_TRANSFORM, column-major
        for (int i = 0; i < 16; ++i) out[i] = (i % 5 == 0) ? 1.0 : 0.0;
        for (int i = 0; i < 3; ++i) out[12 + i] = g_path[i] + g_path[3 + i] * t;
    }
}
void hdGetIntegerv(unsigned int what, int* out)
{
    if (what == 0x2000) *out = g_buttons_from >= 0 && g_frame >= g_buttons_from ? 1 : 0;
}
void hdSetDoublev(unsigned int what, const double* f)
{
    if (what != 0x2700) return; // HD_CURRENT_FORCE
    const long n = g_recorded;
    if (n < k_max_frames) {
        for (int i = 0; i < 3; ++i) g_forces[n][i] = g_force_enabled ? f[i] : 0.0;
        g_recorded = n + 1;
    }
}
const char* hdGetString(unsigned int what)
{
    if (what == 0x2501) return "Touch (fake)";
    if (what == 0x2504) return "41295300123";
    return nullptr;
}
void hdEnable(unsigned int what)
{
    if (what == 0x4000) g_force_enabled = true;
}
void hdStartScheduler()
{
    if (g_running.exchange(true)) return;
    g_thread = std::thread(servo);
}
void hdStopScheduler()
{
    if (!g_running.exchange(false)) return;
    g_thread.join();
}
unsigned long hdScheduleAsynchronous(Callback c, void* user, unsigned short)
{
    std::lock_guard lock(g_mutex);
    g_callback = c;
    g_user = user;
    return 1;
}
void hdScheduleSynchronous(Callback c, void* user, unsigned short) { c(user); }
void hdUnschedule(unsigned long)
{
    std::lock_guard lock(g_mutex);
    g_callback = nullptr;
}
ErrorInfo hdGetError() { return {g_error, g_error ? 42 : 0, 1}; }
const char* hdGetErrorString(unsigned int code)
{
    if (code == static_cast<unsigned int>(k_comm_error)) return "HD_COMM_ERROR (fake): the device stopped answering";
    if (code == static_cast<unsigned int>(k_no_device)) return "HD_DEVICE_FAULT (fake): no device connected";
    return "unknown error";
}
unsigned int hdCheckCalibration() { return g_manual_calibration ? 0x5002 : 0x5000; }
void hdUpdateCalibration(unsigned int) {}

/// The forces set so far (one per frame), up to `max`; returns how many.
long fake_hd_forces(double (*out)[3], long max)
{
    const long n = g_recorded < max ? static_cast<long>(g_recorded) : max;
    for (long i = 0; i < n; ++i)
        for (int k = 0; k < 3; ++k) out[i][k] = g_forces[i][k];
    return n;
}
}
