// The force-feedback backends against fake vendor libraries built by the tests
// (fake_libhd.cpp, fake_libdhd.cpp): discovery and the errors a user meets (no library, a library
// that is not the vendor's, no device, no calibration), unit conversion, forces clamped to the
// device's maximum, OpenHaptics' scheduler ticking the loop at 1 kHz, and a fault mid-session
// answered with zero force, the state held, and the device picked up again when it answers.

#include "haptics/forcedimension_device.hpp"
#include "haptics/haptic_loop.hpp"
#include "haptics/openhaptics_device.hpp"

#include "core/error.hpp"

#include <dlfcn.h>
#include <gtest/gtest.h>

#include <array>
#include <atomic>
#include <chrono>
#include <cstdlib>
#include <string>
#include <thread>
#include <vector>

using namespace vox::haptics;

namespace {
const std::string k_libhd = VOX_FAKE_VENDOR_DIR "/libHD.so";
const std::string k_libdhd = VOX_FAKE_VENDOR_DIR "/libdhd.so";

using Forces = std::vector<std::array<double, 3>>;

/// The forces the fake library `path` was sent, through its own fake_*_forces entry point.
Forces recorded(const std::string& path, const char* symbol)
{
    void* h = ::dlopen(path.c_str(), RTLD_NOW | RTLD_NOLOAD); // the device's own copy
    EXPECT_NE(h, nullptr) << path;
    auto get = reinterpret_cast<long (*)(double (*)[3], long)>(::dlsym(h, symbol));
    Forces out(200000);
    out.resize(static_cast<std::size_t>(get(reinterpret_cast<double (*)[3]>(out.data()), static_cast<long>(out.size()))));
    ::dlclose(h);
    return out;
}

/// The message of the InputError `f` throws ("" when it does not).
template <class F> std::string refusal(F&& f)
{
    try {
        f();
    } catch (const vox::InputError& e) {
        return e.what();
    }
    return "";
}

SafetySettings no_ramp(double max_force_n)
{
    SafetySettings s;
    s.max_force_n = max_force_n;
    s.ramp_s = 0.0;
    return s;
}
} // namespace

TEST(VendorDevices, WithoutTheLibrariesEachBackendSaysWhichLibraryIsMissing)
{
    ::setenv("VOX_LIBHD", "/nonexistent/libHD.so", 1);
    ::setenv("VOX_LIBDHD", "/nonexistent/libdhd.so", 1);
    const std::string hd = refusal([] { OpenHapticsDevice d; });
    EXPECT_EQ(hd.rfind("/nonexistent/libHD.so not found (from VOX_LIBHD): ", 0), 0u) << hd;
    EXPECT_NE(OpenHapticsDevice::probe().problem.find("libHD.so not found"), std::string::npos);
    const std::vector<ForceDeviceInfo> dhd = ForceDimensionDevice::probe();
    ASSERT_EQ(dhd.size(), 1u);
    EXPECT_NE(dhd[0].problem.find("/nonexistent/libdhd.so not found"), std::string::npos) << dhd[0].problem;
    // A file that is not a library: the loader's reason.
    ::setenv("VOX_LIBHD", VOX_SOURCE_DIR "/README.md", 1);
    const std::string not_elf = refusal([] { OpenHapticsDevice d; });
    EXPECT_NE(not_elf.find("README.md cannot be loaded (from VOX_LIBHD): "), std::string::npos) << not_elf;
    // Searched by the loader when no variable names it: the message says how to point at it.
    ::unsetenv("VOX_LIBHD");
    const std::string searched = refusal([] { OpenHapticsDevice d; });
    EXPECT_NE(searched.find("libHD.so not found (searched by the dynamic loader: set LD_LIBRARY_PATH, or VOX_LIBHD"), std::string::npos)
        << searched;
}

TEST(VendorDevices, ALibraryWithoutTheVendorsFunctionsIsNamedWithTheMissingOne)
{
    ::setenv("VOX_LIBDHD", k_libhd.c_str(), 1); // HD's library where DHD's is expected
    const std::string why = refusal([] { ForceDimensionDevice d; });
    EXPECT_NE(why.find("libHD.so: the library has no function dhdGetDeviceCount"), std::string::npos) << why;
}

TEST(VendorDevices, NoDeviceAndNoCalibrationAreSaidInTheVendorsWords)
{
    ::setenv("VOX_LIBHD", k_libhd.c_str(), 1);
    ::setenv("FAKE_HD_NO_DEVICE", "1", 1);
    const std::string none = refusal([] { OpenHapticsDevice d; });
    EXPECT_NE(none.find("cannot open the default device: HD_DEVICE_FAULT (fake): no device connected"), std::string::npos) << none;
    ::unsetenv("FAKE_HD_NO_DEVICE");
    ::setenv("FAKE_HD_CALIBRATION", "manual", 1);
    const std::string uncalibrated = refusal([] { OpenHapticsDevice d; });
    EXPECT_NE(uncalibrated.find("Touch (fake)"), std::string::npos) << uncalibrated;
    EXPECT_NE(uncalibrated.find("not calibrated: put the stylus in its inkwell"), std::string::npos) << uncalibrated;
    ::unsetenv("FAKE_HD_CALIBRATION");

    ::setenv("VOX_LIBDHD", k_libdhd.c_str(), 1);
    ::setenv("FAKE_DHD_COUNT", "0", 1);
    const std::vector<ForceDeviceInfo> found = ForceDimensionDevice::probe();
    ASSERT_EQ(found.size(), 1u);
    EXPECT_NE(found[0].problem.find("no device (is it plugged in and powered"), std::string::npos) << found[0].problem;
    ::setenv("FAKE_DHD_COUNT", "2", 1);
    const std::vector<ForceDeviceInfo> two = ForceDimensionDevice::probe();
    ASSERT_EQ(two.size(), 2u);
    EXPECT_EQ(two[1].model, "omega.6 (fake)");
    EXPECT_EQ(two[1].serial, "1207");
    EXPECT_DOUBLE_EQ(two[1].max_force_n, 12.0);
}

TEST(VendorDevices, OpenHapticsSchedulerTicksTheLoopAtOneKilohertzAndForcesAreClamped)
{
    ::setenv("VOX_LIBHD", k_libhd.c_str(), 1);
    ::setenv("FAKE_HD_PATH", "10 -20 30 5 0 0", 1); // mm, mm/s
    OpenHapticsDevice device;
    EXPECT_EQ(device.name(), "OpenHaptics Touch (fake)");
    EXPECT_EQ(device.info().serial, "41295300123");
    EXPECT_DOUBLE_EQ(device.limits().max_force_n, 3.3);
    // A model asking for 10 N along -z: the device gets its maximum, 3.3 N, pointing the same way.
    std::atomic<double> seen_x{0.0};
    HapticLoop loop(device,
                    [&](const DeviceState& s, double& age) {
                        age = 0.0;
                        seen_x.store(s.position_mm.x(), std::memory_order_relaxed);
                        return Eigen::Vector3d(0, 0, -10.0);
                    },
                    no_ramp(device.limits().max_force_n));
    loop.start();
    std::this_thread::sleep_for(std::chrono::milliseconds(300));
    loop.stop();
    const Forces f = recorded(k_libhd, "fake_hd_forces");
    ASSERT_GT(f.size(), 150u) << "ticks in 0.3 s";
    EXPECT_EQ(loop.timings().force_us.size(), f.size());
    for (const auto& v : f) {
        EXPECT_DOUBLE_EQ(v[0], 0.0);
        EXPECT_NEAR(v[2], -3.3, 1e-12);
    }
    // The position in mm, along the path: 10 mm + 5 mm/s x (frame / 1 kHz).
    const double x = seen_x.load();
    EXPECT_GT(x, 10.0);
    EXPECT_LT(x, 10.0 + 5.0 * 1e-3 * static_cast<double>(f.size()) + 1e-9);
}

TEST(VendorDevices, ForceDimensionPollsInMetresAndAFaultMidSessionZeroesTheForceUntilItAnswers)
{
    ::setenv("VOX_LIBDHD", k_libdhd.c_str(), 1);
    ::setenv("FAKE_DHD_PATH", "0.01 0.02 -0.03 0.1 0 0", 1); // m, m/s
    ::setenv("FAKE_DHD_FAULT", "100 150", 1);
    ::setenv("FAKE_DHD_BUTTONS_FROM", "20", 1);
    ForceDimensionDevice device;
    EXPECT_EQ(device.name(), "Force Dimension omega.6 (fake)");
    HapticLoop loop(device, [](const DeviceState&, double& age) {
        age = 0.0;
        return Eigen::Vector3d(30.0, 40.0, 0.0); // 50 N: clamped to 12 N, same direction
    }, no_ramp(device.limits().max_force_n));
    for (int t = 0; t < 300; ++t) {
        loop.tick(1e-3 * t);
        const DeviceState& s = loop.state();
        if (t == 10) {
            EXPECT_NEAR(s.position_mm.x(), 10.0 + 1.0, 1e-9); // 0.01 m + 0.1 m/s x 10 ms, in mm
            EXPECT_NEAR(s.position_mm.y(), 20.0, 1e-9);
            EXPECT_NEAR(s.position_mm.z(), -30.0, 1e-9);
            EXPECT_EQ(s.buttons, 0u);
        }
        if (t == 30) EXPECT_EQ(s.buttons, 1u);
        if (t == 99) EXPECT_EQ(device.fault(), nullptr);
        if (t == 120) {
            ASSERT_NE(device.fault(), nullptr);
            EXPECT_STREQ(device.fault(), "communication error between the host and the haptic device (fake)");
            EXPECT_NEAR(s.position_mm.x(), 10.0 + 9.9, 1e-9) << "held where the last good poll left it";
        }
        if (t == 200) {
            EXPECT_EQ(device.fault(), nullptr) << "picked up again";
            EXPECT_NEAR(s.position_mm.x(), 10.0 + 20.0, 1e-9);
        }
    }
    const Forces f = recorded(k_libdhd, "fake_dhd_forces");
    ASSERT_EQ(f.size(), 300u);
    for (std::size_t t = 0; t < f.size(); ++t) {
        const bool faulted = t >= 100 && t < 150;
        EXPECT_NEAR(f[t][0], faulted ? 0.0 : 12.0 * 0.6, 1e-12) << t;
        EXPECT_NEAR(f[t][1], faulted ? 0.0 : 12.0 * 0.8, 1e-12) << t;
    }
}

TEST(VendorDevices, AForceDimensionDeviceUnpluggedMidSessionIsOpenedAgainWhenItReturnsAndItsForceRampsBackIn)
{
    ::setenv("VOX_LIBDHD", k_libdhd.c_str(), 1);
    ::setenv("FAKE_DHD_PATH", "0 0 0 0.01 0 0", 1);
    ::unsetenv("FAKE_DHD_FAULT");
    ::setenv("FAKE_DHD_UNPLUG", "50 1", 1); // pulled at poll 50; the first reopening finds no device
    ForceDimensionDevice device;
    SafetySettings safety = no_ramp(device.limits().max_force_n);
    safety.ramp_s = 0.1;
    HapticLoop loop(device, [](const DeviceState&, double& age) {
        age = 0.0;
        return Eigen::Vector3d(0.0, 0.0, 5.0);
    }, safety);
    auto opens = reinterpret_cast<long (*)()>(::dlsym(::dlopen(k_libdhd.c_str(), RTLD_NOW | RTLD_NOLOAD), "fake_dhd_opens"));
    ASSERT_NE(opens, nullptr);
    // The loop at 1 kHz (ticked here), the simulation's recover() between its "frames" of 10 ticks.
    const auto start = std::chrono::steady_clock::now();
    double t = 0.0, faulted_at = -1.0, back_at = -1.0;
    Eigen::Vector3d held = Eigen::Vector3d::Zero();
    while (t < 5.0 && back_at < 0.0) {
        for (int k = 0; k < 10; ++k, t += 1e-3) loop.tick(t);
        if (device.fault() && faulted_at < 0.0) {
            faulted_at = t;
            held = loop.state().position_mm;
        }
        if (faulted_at >= 0.0 && !device.fault()) back_at = t;
        device.recover();
        std::this_thread::sleep_until(start + std::chrono::duration<double>(t));
    }
    ASSERT_GE(faulted_at, 0.0) << "the cable was pulled";
    EXPECT_STREQ(device.fault(), nullptr);
    ASSERT_GE(back_at, 0.0) << "taken up again";
    // Half a second of fault before the first reopening, which finds nothing; the next one, half
    // a second later, opens it.
    EXPECT_GE(back_at - faulted_at, 0.9);
    EXPECT_LT(back_at - faulted_at, 1.5);
    EXPECT_EQ(opens(), 2);
    EXPECT_NEAR(held.x(), 0.49, 1e-9) << "held at the last good poll (49 ms at 10 mm/s)";
    // Back: the force ramps in from zero over the safety stage's ramp, not at once.
    const Eigen::Vector3d first = loop.force();
    EXPECT_LT(first.z(), 5.0 * 0.15);
    for (int k = 0; k < 150; ++k, t += 1e-3) loop.tick(t);
    EXPECT_NEAR(loop.force().z(), 5.0, 1e-12);
    ::unsetenv("FAKE_DHD_UNPLUG");
}
