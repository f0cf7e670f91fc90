#include "core/child_process.hpp"

#include <gtest/gtest.h>

#include <chrono>
#include <csignal>
#include <stdexcept>
#include <thread>
#include <vector>

using vox::ChildLimits;
using vox::ChildOutcome;
using vox::run_in_child;

namespace {
constexpr std::uint64_t k_mib = std::uint64_t{1} << 20;
}

TEST(ChildProcess, WorkThatReturnsIsOk)
{
    int touched = 0;
    const ChildOutcome out = run_in_child([&] { touched = 1; }, {64 * k_mib, 10.0});
    EXPECT_EQ(out.kind, ChildOutcome::Kind::ok);
    EXPECT_EQ(touched, 0); // the child's memory is its own
}

TEST(ChildProcess, AnExceptionComesBackWithItsMessage)
{
    const ChildOutcome out = run_in_child([] { throw std::runtime_error("count 4294967295 is absurd"); },
                                          {64 * k_mib, 10.0});
    EXPECT_EQ(out.kind, ChildOutcome::Kind::failed);
    EXPECT_EQ(out.message, "count 4294967295 is absurd");
}

TEST(ChildProcess, MemoryBeyondTheLimitIsOutOfMemory)
{
    const ChildOutcome out = run_in_child(
        [] {
            std::vector<std::vector<char>> blocks;
            for (int i = 0; i < 64; ++i) blocks.emplace_back(16 * k_mib, 'x'); // 1 GiB in all
        },
        {256 * k_mib, 30.0});
    EXPECT_EQ(out.kind, ChildOutcome::Kind::out_of_memory);
}

TEST(ChildProcess, WorkThatNeverEndsIsKilledInTime)
{
    const auto start = std::chrono::steady_clock::now();
    const ChildOutcome out = run_in_child(
        [] {
            for (;;) std::this_thread::sleep_for(std::chrono::milliseconds(10));
        },
        {64 * k_mib, 0.3});
    const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    EXPECT_EQ(out.kind, ChildOutcome::Kind::timed_out);
    EXPECT_LT(seconds, 5.0);
}

TEST(ChildProcess, ACrashIsReportedWithItsSignal)
{
    const ChildOutcome out = run_in_child([] { std::raise(SIGSEGV); }, {64 * k_mib, 10.0});
    EXPECT_EQ(out.kind, ChildOutcome::Kind::crashed);
    EXPECT_EQ(out.signal, SIGSEGV);
    EXPECT_EQ(vox::signal_name(out.signal), "SIGSEGV");
}
