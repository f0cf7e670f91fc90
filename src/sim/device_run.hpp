#pragma once
// Tools driven by devices in a headless run. Each device has its own virtual coupling holding its
// tool (the proxy) against a snapshot of the surface near that tool, published once per frame,
// and its own safety stage; one haptic loop serves them all; the proxies' poses are where the
// simulation puts the tools. Two ways to run:
//  - lockstep (scripted devices, replays): the loop is ticked by the simulation thread every
//    simulated millisecond, so a run is deterministic and every tick can be recorded
//    (docs/recording-format.md) and replayed bit for bit;
//  - live (a force-feedback device: OpenHaptics, Force Dimension): the loop runs at 1 kHz of wall
//    clock on its own thread (or the vendor's servo thread), the run's frames are paced to wall
//    time, and the two threads share only triple buffers (the snapshot out, the proxy back) and a
//    ring of the ticks' readings and forces, which the simulation thread records each frame.
// A force-feedback device's second button switches its tool's action on while held; a device
// that faults is said in the log, gets no force, holds its tool and is taken up again.

#include "sim/frame_loop.hpp"
#include "sim/level_governor.hpp"
#include "sim/method.hpp"
#include "sim/tool_policy.hpp"
#include "contact/surface_points.hpp"
#include "haptics/coupled_tool.hpp"
#include "haptics/framed_device.hpp"
#include "haptics/haptic_loop.hpp"
#include "haptics/recording.hpp"
#include "haptics/tick_ring.hpp"
#include "haptics/triple_buffer.hpp"
#include "haptics/virtual_device.hpp"

#include <atomic>
#include <chrono>
#include <filesystem>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

namespace vox::sim {

/// One row of forces.csv: the tool's position and the force on the device (or, without a
/// device, on the tool), world.
struct ForceSample {
    double t_s = 0.0;
    Eigen::Vector3d position_mm = Eigen::Vector3d::Zero();
    Eigen::Vector3d force_n = Eigen::Vector3d::Zero();
};

struct DeviceOptions {
    /// The devices, one per entry (`run --device KIND`): "script" (the tool's script, lockstep),
    /// "openhaptics" or "forcedimension" (a force-feedback device: the run is live). No entry:
    /// one scripted device.
    std::vector<std::string> devices;
    /// The scene tool each device drives, by name, in the same order (`--tool NAME`); an empty
    /// name or no entry: the scene's first tool (with a replay: the recording's own devices).
    std::vector<std::string> tools;
    /// Play this recording instead: each device it holds drives the tool it recorded (a recording
    /// made before several devices: tools.front(), or the first tool).
    std::optional<std::filesystem::path> replay;
};

class DeviceRun {
public:
    /// Opens the devices. Throws InputError for an unknown tool or device, a tool driven twice, a
    /// tool without script entries (script device), a device that cannot be opened, a bad
    /// recording, or more than haptics::k_max_devices devices.
    DeviceRun(const io::Scene& scene, const ToolPolicy& tools, const DeviceOptions& options);
    ~DeviceRun();
    DeviceRun(const DeviceRun&) = delete; // the loop's force models refer to this object
    DeviceRun& operator=(const DeviceRun&) = delete;

    /// The frame [t0, t0 + dt): lockstep, runs the haptic ticks of every device against the
    /// surface as `method` has it now (sim/haptic_snapshot.hpp); live, starts the loop at the
    /// first frame, takes the ticks it ran since the last frame and publishes the surface near
    /// where each tool is now. Then tells `tools` where the devices put their tools and whether
    /// their action is on, says faults in the log, and appends to forces() and recording().
    void frame(Method& method, ToolPolicy& tools, double t0_s, double dt_s);
    /// After the last frame: a live loop stopped and its last ticks taken.
    void finish(const Method& method);

    /// The haptic loop runs at 1 kHz of wall clock (a force-feedback device): the run's frames
    /// are to be paced to wall time.
    [[nodiscard]] bool live() const { return m_live; }
    /// A live loop's figures after finish(): ticks, their rate, the period error and force time.
    [[nodiscard]] nlohmann::json loop_figures() const;

    [[nodiscard]] std::size_t device_count() const { return m_hands.size(); }
    /// The scene tool device `i` drives.
    [[nodiscard]] std::size_t tool(std::size_t i = 0) const { return m_hands[i]->tool; }
    /// Device `i`'s force at every tick.
    [[nodiscard]] const std::vector<ForceSample>& forces(std::size_t i = 0) const { return m_hands[i]->forces; }
    /// Every device's ticks, tick by tick.
    [[nodiscard]] const std::vector<haptics::RecordedTick>& recording() const { return m_recording; }
    [[nodiscard]] std::string device_name(std::size_t i = 0) const { return m_hands[i]->device->name(); }
    /// The times device `i` faulted (a cable pulled, an error in its servo loop).
    [[nodiscard]] int faults(std::size_t i = 0) const { return m_hands[i]->faults; }
    /// Each device's contact patch over the last frame.
    [[nodiscard]] std::vector<PatchFrame> patches() const;

    /// A recording is being replayed: the run follows its levels, not a governor.
    [[nodiscard]] bool replaying() const { return !m_replayed.empty(); }
    /// Replaying: the level the recording's first tick after `t0_s` ran at, and the reason it
    /// gave for being there; nothing without a replay or for a recording without levels.
    [[nodiscard]] std::optional<int> recorded_level(double t0_s) const;
    [[nodiscard]] std::string recorded_reason(double t0_s) const;
    /// The simulation moved to another level: the next tick recorded says so, and why.
    void level_changed(const LevelChange& change) { m_level_change = change.reason; }

private:
    /// A tick of a device, as the haptic loop leaves it for the simulation thread.
    struct HandTick {
        double t_s = 0.0;                  ///< loop time
        haptics::DeviceState state;
        Eigen::Vector3d force_n = Eigen::Vector3d::Zero();  ///< sent
        Eigen::Vector3d proxy_mm = Eigen::Vector3d::Zero(); ///< the proxy after the tick
        double patch_us = 0.0;
    };
    /// Where the haptic loop left a device's tool (the newest), and what the device says.
    struct HandPose {
        contact::PlacedShape pose;         ///< where the simulation is to put the tool
        Eigen::Vector3d driver_mm = Eigen::Vector3d::Zero();
        double coupling_n_per_mm = 0.0;
        std::uint32_t buttons = 0;
        bool touching = false;
        double patch_displacement_mm = 0.0;
    };
    /// One device and what it drives; the loop's side and the simulation's.
    struct Hand {
        Hand();
        std::size_t tool = 0;
        std::unique_ptr<haptics::Device> device;
        std::unique_ptr<haptics::CoupledTool> coupled;
        bool arms = false; ///< its second button switches the tool's action on (force-feedback devices)
        haptics::TripleBuffer<contact::SurfacePoints> snapshots; ///< simulation -> loop
        haptics::TripleBuffer<HandPose> poses;                   ///< loop -> simulation
        haptics::TickRing<HandTick> ticks;                       ///< loop -> simulation
        // The simulation thread's own:
        HandPose pose;
        std::size_t patch_points = 0;
        int patch_level = 0;
        double patch_compliance_mm_per_n = 0.0;
        std::vector<ForceSample> forces;
        double patch_us_max = 0.0; ///< this frame's longest patch step
        bool warned_truncated = false;
        const char* fault_said = nullptr;
        int faults = 0;
    };
    void add_hand(std::size_t tool, std::unique_ptr<haptics::Device> device, const ToolPolicy& tools, bool arms);
    /// Each device's proxy put at the device (lockstep: read now; live: its frame's origin, until
    /// the loop's first tick).
    void start(const Method& method, double t0_s);
    /// The surface near each tool, published for the loop, stamped `t_s` (the loop's clock).
    void publish_snapshots(Method& method, double t_s);
    /// The ticks the loop left since the last call, recorded; the newest poses taken.
    void take_ticks(const Method& method);
    /// Faults said once each, and devices that faulted asked to come back.
    void watch_faults();
    [[nodiscard]] double live_now_s() const;

    const io::Scene& m_scene;
    std::vector<std::unique_ptr<Hand>> m_hands;
    std::vector<haptics::RecordedTick> m_replayed;    ///< the recording replayed (all devices), if any
    std::string m_level_change;                       ///< for the next tick recorded
    std::unique_ptr<haptics::HapticLoop> m_loop;
    std::vector<haptics::RecordedTick> m_recording;
    bool m_started = false;
    bool m_live = false;
    std::atomic<double> m_simulation_t_s{0.0};        ///< the last frame's time, for scripted devices of a live run
    std::chrono::steady_clock::time_point m_live_start;
    double m_tick_s = 1e-3;
};

/// The coupling spring of a device driving `tool`: the tool's coupling_stiffness_n_per_mm where
/// the scene gives it, else the haptic default, at most what the device renders stably.
[[nodiscard]] haptics::CouplingSettings device_coupling(const io::ToolSpec& tool, const haptics::DeviceLimits& limits);

/// The scene tool named `name` (empty: the first); InputError naming --tool and the scene's tools
/// when there is none.
[[nodiscard]] std::size_t tool_named(const io::Scene& scene, const std::string& name);
/// InputError for more devices than haptics::k_max_devices, or a tool driven by two of them
/// (`tools`: the tool each device drives).
void check_device_tools(const io::Scene& scene, const std::vector<std::size_t>& tools);
/// The frame a force-feedback device driving `tool` is seen through: the tool's "device_frame",
/// else its origin at `start_mm` (where the tool starts), the scene's axes, scale 1.
[[nodiscard]] haptics::DeviceFrame device_frame(const io::ToolSpec& tool, const Eigen::Vector3d& start_mm);
/// The key frames of `tool`'s script, for a scripted device; InputError when it has none.
[[nodiscard]] std::vector<haptics::KeyFrame> script_key_frames(const io::Scene& scene, std::size_t tool);

/// Writes NAME.csv (t_s, x_mm, y_mm, z_mm, fx_n, fy_n, fz_n) and NAME.svg (the force's magnitude
/// against time) into `dir`.
void write_forces(const std::filesystem::path& dir, const std::vector<ForceSample>& samples, const std::string& title,
                  const std::string& name = "forces");

} // namespace vox::sim
