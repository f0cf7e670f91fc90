#pragma once
// The haptic loop: every millisecond, for each device it serves, read the device, compute the
// force, pass it through that device's safety stage, send it. One loop serves every device of a
// session (two hands, two tools): one thread, one deadline, the devices in turn. Two ways to drive it:
//  - live: its own thread on absolute deadlines (sleep until shortly before the deadline, spin the
//    rest; real-time priority where the system allows it), timing every period and every tick's
//    force computation (all devices) into preallocated buffers; or, when a device's vendor runs
//    its own servo thread (OpenHaptics' scheduler), ticked from that thread, timed the same way;
//  - lockstep: tick(t) called by the simulation thread a fixed number of times per step, in
//    simulated time, so headless runs and replays are deterministic.
// A tick reads every device and sends every force first; then each channel may prepare the next
// tick's work that does not depend on its device (its contact, haptics/coupled_tool.hpp) in the
// rest of the millisecond. The force time is the first part, what the user waits for; the tick's
// work is both.
// The tick never allocates, locks, logs or throws.

#include "haptics/device.hpp"
#include "haptics/force_safety.hpp"

#include <atomic>
#include <chrono>
#include <functional>
#include <thread>
#include <vector>

namespace vox::haptics {

/// Force (N) on the device for its state; must not allocate, lock or throw. `snapshot_age_s` is
/// set to the age of the contact data the force came from.
using ForceModel = std::function<Eigen::Vector3d(const DeviceState& state, double& snapshot_age_s)>;

struct LoopTimings {
    std::vector<double> period_error_ms; ///< |actual period - 1 ms| per tick (live mode)
    std::vector<double> force_us;        ///< per tick: from reading the first device to sending the last force
    std::vector<double> work_us;         ///< per tick: all of it, the channels' preparing included
    bool realtime_priority = false;      ///< SCHED_FIFO was granted
};

/// After every force of a tick is sent, with the state the device was read in: the next tick's
/// work that does not depend on its device's next state. Must not allocate, lock or throw.
using Prepare = std::function<void(const DeviceState& state)>;

/// One device the loop serves: its force model, its own safety stage and, optionally, what it
/// prepares for the next tick.
struct HapticChannel {
    Device* device = nullptr;
    ForceModel model;
    SafetySettings safety;
    Prepare prepare;
};

class HapticLoop {
public:
    /// `capacity`: ticks whose timings are kept (live mode), allocated here.
    HapticLoop(std::vector<HapticChannel> channels, std::size_t capacity = 60000);
    /// One device.
    HapticLoop(Device& device, ForceModel model, const SafetySettings& safety, std::size_t capacity = 60000);
    ~HapticLoop();
    HapticLoop(const HapticLoop&) = delete;
    HapticLoop& operator=(const HapticLoop&) = delete;

    /// One tick at loop time t_s (lockstep mode), every device in turn; returns the force sent to
    /// the first.
    Eigen::Vector3d tick(double t_s) noexcept;

    void start();        ///< live mode: starts the 1 kHz thread, or a device's own servo ticks it
    void stop();         ///< joins the thread (or stops the servo)
    /// Live mode: started and not stopped.
    [[nodiscard]] bool running() const { return m_running.load(std::memory_order_relaxed); }
    /// The live thread's timings so far (call after stop()).
    [[nodiscard]] const LoopTimings& timings() const { return m_timings; }
    [[nodiscard]] std::size_t device_count() const { return m_channels.size(); }
    /// The last tick's force time and whole work, us (LoopTimings), in either mode.
    [[nodiscard]] double last_force_us() const { return m_last_force_us; }
    /// The loop time of the last tick, s (a channel's prepare() may read it).
    [[nodiscard]] double last_tick_s() const { return m_last_t_s; }
    [[nodiscard]] double last_work_us() const { return m_last_work_us; }
    /// Device i's state read and force sent at the last tick.
    [[nodiscard]] const DeviceState& state(std::size_t i = 0) const { return m_channels[i].state; }
    [[nodiscard]] const Eigen::Vector3d& force(std::size_t i = 0) const { return m_channels[i].force; }

private:
    struct Served {
        Device* device;
        ForceModel model;
        Prepare prepare;
        ForceSafety safety;
        DeviceState state;
        Eigen::Vector3d force = Eigen::Vector3d::Zero();
    };
    void run();
    /// A tick from a device's own servo thread (Device::run_servo).
    static void servo_tick(void* self) noexcept;
    /// Keeps this tick's timings (live mode), `now` its start.
    void record(std::chrono::steady_clock::time_point now) noexcept;

    std::vector<Served> m_channels;
    LoopTimings m_timings;
    std::size_t m_recorded = 0;
    double m_last_force_us = 0.0, m_last_work_us = 0.0, m_last_t_s = 0.0;
    std::atomic<bool> m_running{false};
    std::thread m_thread;
    Device* m_servo = nullptr; ///< the device whose servo thread ticks the loop (live mode), if any
    std::chrono::steady_clock::time_point m_start, m_previous;
};

} // namespace vox::haptics
