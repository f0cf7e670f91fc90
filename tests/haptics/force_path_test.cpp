// The haptic loop's safety stage and its lock-free snapshot hand-over, with injected faults.

#include "haptics/force_safety.hpp"
#include "haptics/triple_buffer.hpp"

#include <gtest/gtest.h>

#include <limits>
#include <thread>

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
