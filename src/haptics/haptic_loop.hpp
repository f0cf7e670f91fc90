#pragma once
// The haptic loop: every millisecond, read the device, compute the force, pass it through the
// safety stage, send it. Two ways to drive it:
//  - live: its own thread on absolute deadlines (sleep until shortly before the deadline, spin the
//    rest; real-time priority where the system allows it), timing every period and every force
//    computation into preallocated buffers;
//  - lockstep: tick(t) called by the simulation thread a fixed number of times per step, in
//    simulated time, so headless runs and replays are deterministic.
// The tick never allocates, locks, logs or throws.

#include "haptics/device.hpp"
#include "haptics/force_safety.hpp"

#include <atomic>
#include <functional>
#include <thread>
#include <vector>

namespace vox::haptics {

/// Force (N) on the device for its state; must not allocate, lock or throw. `snapshot_age_s` is
/// set to the age of the contact data the force came from.
using ForceModel = std::function<Eigen::Vector3d(const DeviceState& state, double& snapshot_age_s)>;

struct LoopTimings {
    std::vector<double> period_error_ms; ///< |actual period - 1 ms| per tick (live mode)
    std::vector<double> force_us;        ///< force computation time per tick
    bool realtime_priority = false;      ///< SCHED_FIFO was granted
};

class HapticLoop {
public:
    /// `capacity`: ticks whose timings are kept (live mode), allocated here.
    HapticLoop(Device& device, ForceModel model, const SafetySettings& safety, std::size_t capacity = 60000);
    ~HapticLoop();
    HapticLoop(const HapticLoop&) = delete;
    HapticLoop& operator=(const HapticLoop&) = delete;

    /// One tick at loop time t_s (lockstep mode); returns the force sent.
    Eigen::Vector3d tick(double t_s) noexcept;

    void start();        ///< live mode: starts the 1 kHz thread
    void stop();         ///< joins it
    /// The live thread's timings so far (call after stop()).
    [[nodiscard]] const LoopTimings& timings() const { return m_timings; }
    [[nodiscard]] const DeviceState& state() const { return m_state; }

private:
    void run();

    Device& m_device;
    ForceModel m_model;
    ForceSafety m_safety;
    DeviceState m_state;
    LoopTimings m_timings;
    std::size_t m_recorded = 0;
    std::atomic<bool> m_running{false};
    std::thread m_thread;
};

} // namespace vox::haptics
