// The 1 kHz path never allocates: a lockstep loop ticking a scripted device through free space,
// a press into a surface snapshot, a jab that the tool's mesh sweep stops at the surface and a
// pull back, and the OpenHaptics and Force Dimension backends through the tests' fake vendor
// libraries, counted by this test program's own operator new (plain and aligned). Eigen's own
// heap use goes to malloc and is not counted; the loop uses fixed-size Eigen types only.

#include "haptics/coupled_tool.hpp"
#include "haptics/forcedimension_device.hpp"
#include "haptics/haptic_loop.hpp"
#include "haptics/openhaptics_device.hpp"
#include "haptics/virtual_device.hpp"
#include "surface_snapshots.hpp"

#include <gtest/gtest.h>

#include <atomic>
#include <cstdlib>
#include <algorithm>
#include <new>

namespace {
std::atomic<long> g_allocations{0};
std::atomic<bool> g_counting{false};
} // namespace

void* operator new(std::size_t size)
{
    if (g_counting.load(std::memory_order_relaxed)) ++g_allocations;
    if (void* p = std::malloc(size ? size : 1)) return p;
    throw std::bad_alloc();
}
void* operator new(std::size_t size, std::align_val_t align)
{
    if (g_counting.load(std::memory_order_relaxed)) ++g_allocations;
    const auto a = static_cast<std::size_t>(align);
    if (void* p = std::aligned_alloc(a, (std::max<std::size_t>(size, 1) + a - 1) / a * a)) return p;
    throw std::bad_alloc();
}
void operator delete(void* p) noexcept { std::free(p); }
void operator delete(void* p, std::size_t) noexcept { std::free(p); }
void operator delete(void* p, std::align_val_t) noexcept { std::free(p); }
void operator delete(void* p, std::size_t, std::align_val_t) noexcept { std::free(p); }

using namespace vox;

TEST(HapticLoop, TicksNeverAllocate)
{
    const contact::SurfacePoints wall = test::flat_wall(41, true); // 1 mm triangles, with their tree
    const contact::ToolShape blade = contact::ToolShape::box({10, 0.5, 4});
    haptics::CoupledTool tool(blade, {0.25, 5.0}, {}, wall.capacity());
    const Eigen::Quaterniond level = Eigen::Quaterniond::Identity();
    haptics::VirtualDevice device({{0.0, {0, 0, 5}, level},
                                   {0.2, {0, 0, 1}, level},   // press
                                   {0.3, {3, 0, 5}, level},
                                   {0.301, {3, 0, -2}, level}, // jab: 7 mm in a tick
                                   {0.4, {3, 0, -2}, level},
                                   {0.5, {0, 0, 5}, level}});  // pull back
    haptics::HapticLoop loop(
        device, [&](const haptics::DeviceState& s, double& age) {
            age = 0.0; // a snapshot always fresh
            return tool.update(s, wall, 1e-3);
        },
        haptics::SafetySettings{});
    loop.tick(0.0);
    int swept = 0, stopped = 0;
    double peak = 0.0, after_jab = 0.0;
    g_allocations = 0;
    g_counting = true;
    for (int k = 1; k <= 500; ++k) {
        peak = std::max(peak, loop.tick(1e-3 * k).norm());
        swept += tool.sweep().swept_mesh();
        stopped += tool.sweep().stopped_by_mesh();
        if (k == 301) after_jab = tool.proxy().position.z();
    }
    g_counting = false;
    EXPECT_EQ(g_allocations.load(), 0);
    EXPECT_GT(swept, 0);
    EXPECT_GT(stopped, 0);     // the jab was stopped at the surface by the mesh sweep
    // The jab's tick ends with the blade's lower face (2 mm below its centre) at the wall (within
    // a quarter of the 0.25 mm margin above it), not 4 mm into it; the penalty then lets it sink
    // in at most a margin a tick.
    EXPECT_GE(after_jab, 2.0);
    EXPECT_LT(after_jab, 2.0 + 0.25 / 4 + 0.0011);
    EXPECT_GT(peak, 0.05);     // and the contact was felt
}

TEST(HapticLoop, OneLoopServesTwoDevicesEachWithItsOwnSafetyWithoutAllocating)
{
    // Two hands on one wall: a blade pressing in and a second blade pressing elsewhere, each
    // coupled on its own; the second device's safety stage allows 0.05 N, the first's 3 N.
    const contact::SurfacePoints wall = test::flat_wall(41, true);
    const contact::ToolShape blade = contact::ToolShape::box({4, 0.5, 4});
    haptics::CoupledTool left(blade, {0.25, 5.0}, {}, wall.capacity()), right(blade, {0.25, 5.0}, {}, wall.capacity());
    const Eigen::Quaterniond level = Eigen::Quaterniond::Identity();
    haptics::VirtualDevice a({{0.0, {-8, 0, 5}, level}, {0.2, {-8, 0, 1}, level}, {0.4, {-8, 0, 1}, level}});
    haptics::VirtualDevice b({{0.0, {8, 0, 5}, level}, {0.3, {8, 0, 1}, level}, {0.4, {8, 0, 1}, level}});
    haptics::SafetySettings gentle;
    gentle.max_force_n = 0.05;
    gentle.ramp_s = 0.0;
    haptics::SafetySettings firm;
    firm.ramp_s = 0.0;
    std::vector<haptics::HapticChannel> channels;
    // Each measures its next contact after the forces are sent (prepare), as a live session does.
    channels.push_back({&a, [&](const haptics::DeviceState& s, double& age) { age = 0.0; return left.update(s, wall, 1e-3); }, firm,
                        [&](const haptics::DeviceState& s) { left.prepare(s, wall, 1e-3); }});
    channels.push_back({&b, [&](const haptics::DeviceState& s, double& age) { age = 0.0; return right.update(s, wall, 1e-3); }, gentle,
                        [&](const haptics::DeviceState& s) { right.prepare(s, wall, 1e-3); }});
    haptics::HapticLoop loop(std::move(channels), 0);
    ASSERT_EQ(loop.device_count(), 2u);
    loop.tick(0.0);
    double peak_a = 0.0, peak_b = 0.0;
    g_allocations = 0;
    g_counting = true;
    for (int k = 1; k <= 400; ++k) {
        loop.tick(1e-3 * k);
        peak_a = std::max(peak_a, loop.force(0).norm());
        peak_b = std::max(peak_b, loop.force(1).norm());
    }
    g_counting = false;
    EXPECT_EQ(g_allocations.load(), 0);
    EXPECT_GT(peak_a, 0.1);                // the first hand feels its press
    EXPECT_NEAR(peak_b, 0.05, 1e-12);      // the second, clamped by its own stage
    EXPECT_EQ(loop.state(1).position_mm, Eigen::Vector3d(8, 0, 1));
    EXPECT_GT(left.proxy().position.x(), -9.0);
    EXPECT_LT(left.proxy().position.x(), -7.0); // each proxy followed its own device
    EXPECT_GT(right.proxy().position.x(), 7.0);
}

TEST(HapticLoop, TheVendorBackendsTickWithoutAllocating)
{
    // Both force-feedback backends (through the tests' fake vendor libraries) served by one loop
    // in lockstep, through a fault of the Force Dimension device and its return.
    ::setenv("VOX_LIBHD", VOX_FAKE_VENDOR_DIR "/libHD.so", 1);
    ::setenv("VOX_LIBDHD", VOX_FAKE_VENDOR_DIR "/libdhd.so", 1);
    ::setenv("FAKE_DHD_FAULT", "100 150", 1);
    haptics::OpenHapticsDevice touch;
    haptics::ForceDimensionDevice omega;
    const haptics::ForceModel push = [](const haptics::DeviceState& s, double& age) {
        age = 0.0;
        return Eigen::Vector3d(0.0, 0.0, -0.01 * s.position_mm.z() - 1.0);
    };
    std::vector<haptics::HapticChannel> channels;
    channels.push_back({&touch, push, haptics::SafetySettings{}, {}});
    channels.push_back({&omega, push, haptics::SafetySettings{}, {}});
    haptics::HapticLoop loop(std::move(channels), 0);
    loop.tick(0.0);
    g_allocations = 0;
    g_counting = true;
    for (int k = 1; k <= 300; ++k) loop.tick(1e-3 * k);
    g_counting = false;
    EXPECT_EQ(g_allocations.load(), 0);
    EXPECT_EQ(omega.fault(), nullptr);
    EXPECT_GT(loop.force(0).norm(), 0.1);
}
