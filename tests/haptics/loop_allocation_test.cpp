// The 1 kHz path never allocates: a lockstep loop ticking a scripted device through free space,
// a press into a surface snapshot, a jab that sweeps the tool's mesh and a pull back, counted by
// this test program's own operator new. (Locks and logs would show here too: spdlog formats into
// allocated buffers, and the mutexes the loop could take are in allocating code.)

#include "haptics/coupled_tool.hpp"
#include "haptics/haptic_loop.hpp"
#include "haptics/virtual_device.hpp"

#include <gtest/gtest.h>

#include <atomic>
#include <cstdlib>
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
void operator delete(void* p) noexcept { std::free(p); }
void operator delete(void* p, std::size_t) noexcept { std::free(p); }

using namespace vox;

TEST(HapticLoop, TicksNeverAllocate)
{
    // A 40 x 40 mm wall of 1 mm triangles at z = 0, with its tree, as the simulation publishes it.
    constexpr int n = 41;
    contact::SurfacePoints wall(n * n);
    for (int i = 0; i < n; ++i)
        for (int j = 0; j < n; ++j) {
            wall.positions_mm[wall.count] = Eigen::Vector3d(i - 20.0, j - 20.0, 0.0);
            wall.normals[wall.count] = Eigen::Vector3d::UnitZ();
            wall.areas_mm2[wall.count++] = 1.0;
        }
    for (int i = 0; i + 1 < n; ++i)
        for (int j = 0; j + 1 < n; ++j) {
            const int a = i * n + j;
            wall.triangles.emplace_back(a, a + n, a + n + 1);
            wall.triangles.emplace_back(a, a + n + 1, a + 1);
        }
    const std::span<const Eigen::Vector3d> p(wall.positions_mm.data(), wall.count);
    wall.triangle_tree.rebuild(p, p, wall.triangles);
    wall.t_s = 0.0;

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
    int swept = 0;
    double peak = 0.0;
    g_allocations = 0;
    g_counting = true;
    for (int k = 1; k <= 500; ++k) {
        peak = std::max(peak, loop.tick(1e-3 * k).norm());
        swept += tool.sweep().swept_mesh();
    }
    g_counting = false;
    EXPECT_EQ(g_allocations.load(), 0);
    EXPECT_GT(swept, 0);  // the jab ran the mesh sweep
    EXPECT_GT(peak, 0.05); // and the contact was felt
}
