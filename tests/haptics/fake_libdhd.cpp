// A stand-in for Force Dimension's libdhd.so, built by the tests as their own libdhd.so: the DHD
// entry points VoxSculpt calls, devices that move along a straight path as they are polled, and a
// record of the forces they are sent. Set by environment variables read at dhdGetDeviceCount:
//   FAKE_DHD_COUNT=n            devices found (default 1)
//   FAKE_DHD_PATH="x y z vx vy vz"  position (m) at poll 0 and velocity (m/s) per poll of 1 ms
//   FAKE_DHD_FAULT="a b"        polls a .. b-1 fail with a communication error
//   FAKE_DHD_BUTTONS_FROM=n     button 0 held from poll n on
//   FAKE_DHD_BUTTON2="a b"      button 1 held from poll a to b-1
//   FAKE_DHD_UNPLUG="a n"       at poll a the cable is pulled: every call fails until the device is
//                               closed and opened again, and the first n openings find no device
// fake_dhd_forces() gives the test the forces set, one per poll; fake_dhd_opens() how many times
// a device was opened. Polls count from dhdGetDeviceCount (a reopened device goes on its path).

#include <cstdio>
#include <cstdlib>

namespace {
constexpr int k_max_polls = 200000;
constexpr int k_comm_error = 4;
double g_path[6] = {0, 0, 0, 0, 0, 0};
long g_fault_from = -1, g_fault_to = -1, g_buttons_from = -1, g_button2_from = -1, g_button2_to = -1;
long g_unplug_at = -1, g_unplug_openings = 0, g_opens = 0;
bool g_unplugged = false;
int g_count = 1;
long g_poll = 0;
int g_error = 0;
bool g_open = false, g_force = false;
double g_forces[k_max_polls][3];
long g_recorded = 0;

bool in_fault() { return g_poll >= g_fault_from && g_poll < g_fault_to; }
} // namespace

extern "C" {

int dhdGetDeviceCount()
{
    g_count = 1;
    if (const char* c = std::getenv("FAKE_DHD_COUNT")) g_count = std::atoi(c);
    if (const char* p = std::getenv("FAKE_DHD_PATH"))
        std::sscanf(p, "%lf %lf %lf %lf %lf %lf", &g_path[0], &g_path[1], &g_path[2], &g_path[3], &g_path[4], &g_path[5]);
    if (const char* f = std::getenv("FAKE_DHD_FAULT")) std::sscanf(f, "%ld %ld", &g_fault_from, &g_fault_to);
    if (const char* b = std::getenv("FAKE_DHD_BUTTONS_FROM")) g_buttons_from = std::atol(b);
    if (const char* b = std::getenv("FAKE_DHD_BUTTON2")) std::sscanf(b, "%ld %ld", &g_button2_from, &g_button2_to);
    if (const char* u = std::getenv("FAKE_DHD_UNPLUG")) std::sscanf(u, "%ld %ld", &g_unplug_at, &g_unplug_openings);
    g_poll = 0;
    g_recorded = 0;
    g_opens = 0;
    g_unplugged = false;
    return g_count;
}
int dhdOpenID(char index)
{
    if (index < 0 || index >= g_count) {
        g_error = 2;
        return -1;
    }
    if (g_unplugged && g_unplug_openings-- > 0) {
        g_error = 2;
        return -1;
    }
    g_unplugged = false;
    g_open = true;
    ++g_opens;
    return index;
}
int dhdClose(char)
{
    g_open = false;
    return 0;
}
const char* dhdGetSystemName(char) { return "omega.6 (fake)"; }
int dhdGetSerialNumber(unsigned short* serial, char)
{
    *serial = 1207;
    return 0;
}
int dhdGetPosition(double* x, double* y, double* z, char)
{
    if (g_poll == g_unplug_at && !g_unplugged && g_opens == 1) g_unplugged = true;
    if (g_unplugged || !g_open) {
        g_error = k_comm_error;
        return -1;
    }
    if (in_fault()) {
        g_error = k_comm_error;
        ++g_poll;
        return -1;
    }
    const double t = static_cast<double>(g_poll) * 1e-3;
    *x = g_path[0] + g_path[3] * t;
    *y = g_path[1] + g_path[4] * t;
    *z = g_path[2] + g_path[5] * t;
    ++g_poll;
    return 0;
}
int dhdGetOrientationFrame(double m[3][3], char)
{
    if (g_unplugged) {
        g_error = k_comm_error;
        return -1;
    }
    for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j) m[i][j] = i == j ? 1.0 : 0.0;
    return 0;
}
unsigned int dhdGetButtonMask(char)
{
    return (g_buttons_from >= 0 && g_poll > g_buttons_from ? 1u : 0u) | (g_poll > g_button2_from && g_poll <= g_button2_to ? 2u : 0u);
}
int dhdSetForce(double fx, double fy, double fz, char)
{
    if (g_unplugged) {
        g_error = k_comm_error;
        return -1;
    }
    if (g_recorded < k_max_polls) {
        g_forces[g_recorded][0] = g_force ? fx : 0.0;
        g_forces[g_recorded][1] = g_force ? fy : 0.0;
        g_forces[g_recorded][2] = g_force ? fz : 0.0;
        ++g_recorded;
    }
    return 0;
}
int dhdEnableForce(unsigned char on, char)
{
    g_force = on != 0;
    return 0;
}
double dhdGetMaxForce(char) { return 12.0; }
int dhdErrorGetLast() { return g_error; }
const char* dhdErrorGetStr(int error)
{
    if (error == k_comm_error) return "communication error between the host and the haptic device (fake)";
    if (error == 2) return "no such device (fake)";
    return "no error";
}

/// How many times a device was opened since dhdGetDeviceCount.
long fake_dhd_opens() { return g_opens; }

/// The forces set so far (one per poll), up to `max`; returns how many.
long fake_dhd_forces(double (*out)[3], long max)
{
    const long n = g_recorded < max ? g_recorded : max;
    for (long i = 0; i < n; ++i)
        for (int k = 0; k < 3; ++k) out[i][k] = g_forces[i][k];
    return n;
}
}
