#pragma once
// Tools driven by devices in a headless run: each device (following the scene script for its
// tool, or replaying a recording) is read every simulated millisecond by the one haptic loop, in
// lockstep with the simulation; each has its own virtual coupling holding its tool (the proxy)
// against a snapshot of the surface near that tool, published once per frame, and its own safety
// stage; the proxies' poses are where the simulation puts the tools. Every tick of every device
// can be recorded (docs/recording-format.md) and replayed bit for bit.

#include "sim/frame_loop.hpp"
#include "sim/level_governor.hpp"
#include "sim/method.hpp"
#include "sim/tool_policy.hpp"
#include "contact/surface_points.hpp"
#include "haptics/coupled_tool.hpp"
#include "haptics/haptic_loop.hpp"
#include "haptics/recording.hpp"
#include "haptics/virtual_device.hpp"

#include <filesystem>
#include <memory>
#include <optional>
#include <string>
#include <vector>

namespace vox::sim {

/// One row of forces.csv: the tool's position and the force on the device (or, without a
/// device, on the tool), world.
struct ForceSample {
    double t_s = 0.0;
    Eigen::Vector3d position_mm = Eigen::Vector3d::Zero();
    Eigen::Vector3d force_n = Eigen::Vector3d::Zero();
};

struct DeviceOptions {
    /// One scripted device per entry, driving the scene tool of that name (`run --device script
    /// --tool NAME`, once per device); an empty name: the scene's first tool. No entry: one device
    /// on the first tool (with a replay: the recording's own devices).
    std::vector<std::string> tools;
    /// Play this recording instead: each device it holds drives the tool it recorded (a recording
    /// made before several devices: tools.front(), or the first tool).
    std::optional<std::filesystem::path> replay;
};

class DeviceRun {
public:
    /// Throws InputError for an unknown tool, a tool driven twice, a tool without script entries
    /// (script device), a bad recording, or more than haptics::k_max_devices devices.
    DeviceRun(const io::Scene& scene, const ToolPolicy& tools, const DeviceOptions& options);
    DeviceRun(const DeviceRun&) = delete; // the loop's force models refer to this object
    DeviceRun& operator=(const DeviceRun&) = delete;

    /// Runs the haptic ticks of the frame [t0, t0 + dt) of every device against the surface as
    /// `method` has it now (sim/haptic_snapshot.hpp), then tells `tools` where the devices put their tools. Appends to
    /// forces() and recording().
    void frame(Method& method, ToolPolicy& tools, double t0_s, double dt_s);

    [[nodiscard]] std::size_t device_count() const { return m_hands.size(); }
    /// The scene tool device `i` drives.
    [[nodiscard]] std::size_t tool(std::size_t i = 0) const { return m_hands[i]->tool; }
    /// Device `i`'s force at every tick.
    [[nodiscard]] const std::vector<ForceSample>& forces(std::size_t i = 0) const { return m_hands[i]->forces; }
    /// Every device's ticks, tick by tick.
    [[nodiscard]] const std::vector<haptics::RecordedTick>& recording() const { return m_recording; }
    [[nodiscard]] std::string device_name(std::size_t i = 0) const { return m_hands[i]->device->name(); }
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
    /// One device and what it drives.
    struct Hand {
        std::size_t tool = 0;
        std::unique_ptr<haptics::Device> device;
        std::unique_ptr<haptics::CoupledTool> coupled;
        contact::SurfacePoints snapshot;
        std::vector<ForceSample> forces;
        double patch_us_max = 0.0; ///< this frame's longest patch step
        bool warned_truncated = false;
    };
    void add_hand(std::size_t tool, std::unique_ptr<haptics::Device> device, const ToolPolicy& tools);

    const io::Scene& m_scene;
    std::vector<std::unique_ptr<Hand>> m_hands;
    std::vector<haptics::RecordedTick> m_replayed;    ///< the recording replayed (all devices), if any
    std::string m_level_change;                       ///< for the next tick recorded
    std::unique_ptr<haptics::HapticLoop> m_loop;
    std::vector<haptics::RecordedTick> m_recording;
    bool m_started = false;
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
/// The key frames of `tool`'s script, for a scripted device; InputError when it has none.
[[nodiscard]] std::vector<haptics::KeyFrame> script_key_frames(const io::Scene& scene, std::size_t tool);

/// Writes NAME.csv (t_s, x_mm, y_mm, z_mm, fx_n, fy_n, fz_n) and NAME.svg (the force's magnitude
/// against time) into `dir`.
void write_forces(const std::filesystem::path& dir, const std::vector<ForceSample>& samples, const std::string& title,
                  const std::string& name = "forces");

} // namespace vox::sim
