#pragma once
// A tool driven by a device in a headless run: the device (following the scene script, or
// replaying a recording) is read every simulated millisecond by the haptic loop in lockstep with
// the simulation; a virtual coupling holds the tool (the proxy) against a snapshot of the surface
// near it, published once per frame; the proxy's pose is where the simulation puts the tool.
// Every tick can be recorded (docs/recording-format.md) and replayed bit for bit.

#include "sim/level_governor.hpp"
#include "sim/method.hpp"
#include "sim/tool_policy.hpp"
#include "contact/surface_points.hpp"
#include "haptics/coupled_tool.hpp"
#include "haptics/haptic_loop.hpp"
#include "haptics/recording.hpp"

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
    std::string tool;                     ///< the scene tool the device drives (empty: the first tool)
    std::optional<std::filesystem::path> replay; ///< play this recording instead of the script
};

class DeviceRun {
public:
    /// Throws InputError for an unknown tool, a tool without script entries (script device), or a
    /// bad recording.
    DeviceRun(const io::Scene& scene, const ToolPolicy& tools, const DeviceOptions& options);
    DeviceRun(const DeviceRun&) = delete; // the loop's force model refers to this object
    DeviceRun& operator=(const DeviceRun&) = delete;

    /// Runs the haptic ticks of the frame [t0, t0 + dt) against the surface as `method` has it
    /// now, then tells `tools` where the device put the tool. Appends to forces() and recording().
    void frame(const Method& method, ToolPolicy& tools, double t0_s, double dt_s);

    [[nodiscard]] std::size_t tool() const { return m_tool; }
    [[nodiscard]] const std::vector<ForceSample>& forces() const { return m_forces; }
    [[nodiscard]] const std::vector<haptics::RecordedTick>& recording() const { return m_recording; }
    [[nodiscard]] std::string device_name() const { return m_device->name(); }

    /// A recording is being replayed: the run follows its levels, not a governor.
    [[nodiscard]] bool replaying() const { return m_replay != nullptr; }
    /// Replaying: the level the recording's first tick after `t0_s` ran at, and the reason it
    /// gave for being there; nothing without a replay or for a recording without levels.
    [[nodiscard]] std::optional<int> recorded_level(double t0_s) const;
    [[nodiscard]] std::string recorded_reason(double t0_s) const;
    /// The simulation moved to another level: the next tick recorded says so, and why.
    void level_changed(const LevelChange& change) { m_level_change = change.reason; }

private:
    const io::Scene& m_scene;
    std::size_t m_tool = 0;
    std::unique_ptr<haptics::Device> m_device;
    const haptics::ReplayDevice* m_replay = nullptr; ///< m_device, when it replays a recording
    std::string m_level_change;                       ///< for the next tick recorded
    std::unique_ptr<haptics::CoupledTool> m_coupled;
    contact::SurfacePoints m_snapshot;
    std::unique_ptr<haptics::HapticLoop> m_loop;
    std::vector<ForceSample> m_forces;
    std::vector<haptics::RecordedTick> m_recording;
    bool m_started = false;
    bool m_warned_truncated = false;
    double m_tick_s = 1e-3;
};

/// Writes forces.csv (t_s, x_mm, y_mm, z_mm, fx_n, fy_n, fz_n) and forces.svg (the force's
/// magnitude against time) into `dir`.
void write_forces(const std::filesystem::path& dir, const std::vector<ForceSample>& samples, const std::string& title);

} // namespace vox::sim
