// The haptic loop's safety stage and its lock-free snapshot hand-over, with injected faults.

#include "haptics/force_safety.hpp"
#include "haptics/tick_ring.hpp"
#include "haptics/triple_buffer.hpp"

#include <gtest/gtest.h>

#include <chrono>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>
#include <thread>
#include <vector>

using namespace vox::haptics;
using Eigen::Vector3d;

namespace {
SafetySettings settings()
{
    SafetySettings s;
    s.max_force_n = 2.0;
    s.ramp_s = 1.0;
    s.stale_s = 0.05;
    s.fade_s = 0.05;
    return s;
}
} // namespace

TEST(ForceSafety, NonFiniteForcesBecomeZeroAndAreCounted)
{
    ForceSafety safety(settings());
    const double nan = std::numeric_limits<double>::quiet_NaN(), inf = std::numeric_limits<double>::infinity();
    EXPECT_EQ(safety.filter({nan, 0, 0}, 5.0, 0.0), Vector3d::Zero());
    EXPECT_EQ(safety.filter({0, inf, 0}, 5.0, 0.0), Vector3d::Zero());
    EXPECT_EQ(safety.filter({0, 0, -inf}, 5.0, 0.0), Vector3d::Zero());
    EXPECT_EQ(safety.non_finite_count(), 3u);
}

TEST(ForceSafety, ClampsToTheDeviceMaximumKeepingDirection)
{
    ForceSafety safety(settings());
    const Vector3d f = safety.filter({30, 40, 0}, 5.0, 0.0);
    EXPECT_NEAR(f.norm(), 2.0, 1e-12);
    EXPECT_NEAR(f.x() / f.y(), 0.75, 1e-12);
    EXPECT_EQ(safety.filter({0.5, 0, 0}, 5.0, 0.0), Vector3d(0.5, 0, 0)); // below the maximum: untouched
    EXPECT_EQ(safety.clamped_count(), 1u);
}

TEST(ForceSafety, RampsInAtStartUp)
{
    ForceSafety safety(settings());
    EXPECT_EQ(safety.filter({1, 0, 0}, 0.0, 0.0), Vector3d::Zero());
    EXPECT_NEAR(safety.filter({1, 0, 0}, 0.25, 0.0).x(), 0.25, 1e-12);
    EXPECT_NEAR(safety.filter({1, 0, 0}, 2.0, 0.0).x(), 1.0, 1e-12);
}

TEST(ForceSafety, RampsInAgainAfterADeviceFault)
{
    ForceSafety safety(settings());
    EXPECT_NEAR(safety.filter({1, 0, 0}, 3.0, 0.0).x(), 1.0, 1e-12);
    safety.hold_off(4.0); // faulted at 4 s (the loop holds off at every faulted tick)
    EXPECT_EQ(safety.filter({1, 0, 0}, 4.0, 0.0), Vector3d::Zero());
    EXPECT_NEAR(safety.filter({1, 0, 0}, 4.5, 0.0).x(), 0.5, 1e-12); // back: half-way up the 1 s ramp
    EXPECT_NEAR(safety.filter({1, 0, 0}, 5.0, 0.0).x(), 1.0, 1e-12);
}

TEST(TickRing, HandsOverEveryValueInOrderAndCountsWhatAFullRingDrops)
{
    TickRing<int> ring(4);
    for (int i = 0; i < 6; ++i) ring.push(i);
    EXPECT_EQ(ring.size(), 4u);
    EXPECT_EQ(ring.dropped(), 2u);
    std::vector<int> got;
    while (ring.size() > 0) {
        got.push_back(ring.front());
        ring.pop();
    }
    EXPECT_EQ(got, (std::vector<int>{0, 1, 2, 3}));
    // Across threads: a writer of 100000 values, a reader taking them as they come.
    TickRing<int> shared(64);
    std::thread writer([&] {
        for (int i = 0; i < 100000; ++i)
            while (!shared.push(i)) std::this_thread::yield();
    });
    int expected = 0;
    bool in_order = true;
    while (expected < 100000) {
        if (shared.size() == 0) continue;
        in_order = in_order && shared.front() == expected;
        shared.pop();
        ++expected;
    }
    writer.join();
    EXPECT_TRUE(in_order);
}

TEST(ForceSafety, FadesOutWhenTheSnapshotIsStale)
{
    ForceSafety safety(settings());
    EXPECT_NEAR(safety.filter({1, 0, 0}, 5.0, 0.05).x(), 1.0, 1e-12);   // 50 ms: still fresh
    EXPECT_NEAR(safety.filter({1, 0, 0}, 5.0, 0.075).x(), 0.5, 1e-12);  // half-way through the fade
    EXPECT_EQ(safety.filter({1, 0, 0}, 5.0, 0.1), Vector3d::Zero());      // faded out
    EXPECT_EQ(safety.filter({1, 0, 0}, 5.0, 10.0), Vector3d::Zero());
    EXPECT_EQ(safety.filter({1, 0, 0}, 5.0, std::numeric_limits<double>::quiet_NaN()), Vector3d::Zero());
}

TEST(TripleBuffer, ReaderSeesTheNewestPublishedValue)
{
    TripleBuffer<int> b(0);
    EXPECT_FALSE(b.update());
    b.write_slot() = 1;
    b.publish();
    b.write_slot() = 2;
    b.publish();
    EXPECT_TRUE(b.update());
    EXPECT_EQ(b.read_slot(), 2);
    EXPECT_FALSE(b.update()); // nothing new
    EXPECT_EQ(b.read_slot(), 2);
}

TEST(TripleBuffer, ConcurrentReaderNeverSeesATornOrOlderValue)
{
    struct Pair {
        long a = 0, b = 0; // b == 2 a in every published value
    };
    TripleBuffer<Pair> buffer;
    constexpr long n = 200000;
    std::thread writer([&] {
        for (long i = 1; i <= n; ++i) {
            Pair& p = buffer.write_slot();
            p.a = i;
            p.b = 2 * i;
            buffer.publish();
        }
    });
    long last = 0;
    bool torn = false, backwards = false;
    while (last < n) {
        if (!buffer.update()) continue;
        const Pair& p = buffer.read_slot();
        torn = torn || p.b != 2 * p.a;
        backwards = backwards || p.a < last;
        last = p.a;
    }
    writer.join();
    EXPECT_FALSE(torn);
    EXPECT_FALSE(backwards);
    EXPECT_EQ(last, n);
}

#include "haptics/haptic_loop.hpp"
#include "haptics/virtual_device.hpp"

namespace {
/// A spring pushing the tool out of the half-space z < 0 (a stand-in for contact).
Eigen::Vector3d floor_spring(const DeviceState& s, double& age)
{
    age = 0.0;
    return s.position_mm.z() < 0 ? Eigen::Vector3d(0, 0, -0.5 * s.position_mm.z()) : Eigen::Vector3d::Zero();
}
} // namespace

TEST(HapticLoop, LockstepTicksAreDeterministicAndSafe)
{
    auto run = [] {
        VirtualDevice device({{0.0, {0, 0, 5}, Eigen::Quaterniond::Identity()}, {0.1, {0, 0, -20}, Eigen::Quaterniond::Identity()}});
        SafetySettings s;
        s.ramp_s = 0.02;
        s.max_force_n = 3.0;
        HapticLoop loop(device, floor_spring, s, 0);
        std::vector<Vector3d> forces;
        for (int k = 0; k <= 100; ++k) forces.push_back(loop.tick(k * 1e-3));
        return forces;
    };
    const auto a = run(), b = run();
    EXPECT_EQ(a, b);
    EXPECT_EQ(a.front(), Vector3d::Zero());                 // above the floor, and ramping in
    EXPECT_NEAR(a.back().norm(), 3.0, 1e-12);               // 10 N asked at 20 mm deep: clamped
    for (const Vector3d& f : a) EXPECT_LE(f.norm(), 3.0 + 1e-12);
}

TEST(HapticLoop, AFaultyModelNeverReachesTheDevice)
{
    VirtualDevice device({{0.0, {0, 0, 0}, Eigen::Quaterniond::Identity()}});
    int calls = 0;
    HapticLoop loop(device,
                    [&calls](const DeviceState&, double& age) -> Vector3d {
                        age = 0.0;
                        if (++calls % 2) return Vector3d(std::numeric_limits<double>::quiet_NaN(), 0, 0);
                        throw std::runtime_error("model failure");
                    },
                    SafetySettings{}, 0);
    for (int k = 0; k < 10; ++k) EXPECT_EQ(loop.tick(5.0 + k * 1e-3), Vector3d::Zero());
}

TEST(HapticLoop, EachChannelPreparesAfterEveryForceIsSent)
{
    // Two devices: a tick reads and answers both before either prepares, each prepare gets the
    // state its model was given, and the force time ends before the tick's work does.
    VirtualDevice a({{0.0, {0, 0, 1}, Eigen::Quaterniond::Identity()}, {1.0, {0, 0, -1}, Eigen::Quaterniond::Identity()}});
    VirtualDevice b({{0.0, {5, 0, 1}, Eigen::Quaterniond::Identity()}});
    std::vector<std::string> calls;
    std::vector<Vector3d> modelled, prepared;
    auto channel = [&](VirtualDevice& device, std::string name) {
        HapticChannel c;
        c.device = &device;
        c.model = [&, name](const DeviceState& s, double& age) {
            calls.push_back("model " + name);
            modelled.push_back(s.position_mm);
            return floor_spring(s, age);
        };
        c.prepare = [&, name](const DeviceState& s) {
            calls.push_back("prepare " + name);
            prepared.push_back(s.position_mm);
        };
        return c;
    };
    std::vector<HapticChannel> channels;
    channels.push_back(channel(a, "a"));
    channels.push_back(channel(b, "b"));
    HapticLoop loop(std::move(channels), 0);
    loop.tick(0.5);
    EXPECT_EQ(calls, (std::vector<std::string>{"model a", "model b", "prepare a", "prepare b"}));
    EXPECT_EQ(prepared, modelled);
    EXPECT_GE(loop.last_work_us(), loop.last_force_us());
    EXPECT_GT(loop.last_force_us(), 0.0);
}

TEST(HapticLoop, LiveThreadTicksAndRecordsItsTimings)
{
    VirtualDevice device({{0.0, {0, 0, 1}, Eigen::Quaterniond::Identity()}});
    HapticLoop loop(device, floor_spring, SafetySettings{}, 10000);
    loop.start();
    std::this_thread::sleep_for(std::chrono::milliseconds(300));
    loop.stop();
    // Not a timing test: only that the thread ran and recorded what it measured.
    EXPECT_GT(loop.timings().period_error_ms.size(), 50u);
    EXPECT_EQ(loop.timings().period_error_ms.size(), loop.timings().force_us.size());
    ASSERT_EQ(loop.timings().work_us.size(), loop.timings().force_us.size());
    for (std::size_t k = 0; k < loop.timings().work_us.size(); ++k) EXPECT_GE(loop.timings().work_us[k], loop.timings().force_us[k]);
    for (double e : loop.timings().period_error_ms) EXPECT_TRUE(std::isfinite(e));
}
