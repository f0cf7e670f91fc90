#pragma once
// The one frame loop: a device's haptic ticks (when a device drives a tool), the tools (contact,
// cuts, wetting: sim/tool_policy.hpp), then the method's step, unless a two-phase tool holds the
// object while it marks its cut. `voxsculpt run`, the viewer, device runs, every bench and the
// tests step through it, so they simulate the same thing. With a level governor (view and device
// runs of a budget scene: sim/level_governor.hpp) a frame may begin by moving the method to
// another level; a replayed recording moves it where the recording says instead.

#include "core/error.hpp"
#include "sim/level_governor.hpp"
#include "sim/method.hpp"
#include "sim/tool_policy.hpp"

#include <optional>
#include <string>
#include <vector>

namespace vox::sim {

class DeviceRun;

/// One frame, as every method reports it.
/// One device's contact patch over a frame (contact/contact_patch.hpp; device runs).
struct PatchFrame {
    std::string tool;
    std::size_t points = 0;            ///< the patch's moving points (0: no patch this frame)
    int level = 0;                     ///< its Loop subdivisions
    double compliance_mm_per_n = 0.0;  ///< the FEM's at the contact, which its springs were scaled to
    double displacement_mm = 0.0;      ///< its largest give at the frame's last tick, handed on with the tool's pose
    double step_us_max = 0.0;          ///< its longest step in the frame's ticks
    bool asked = false;                ///< the tool asks for one (its haptic_subdivision)
    bool touching = false;             ///< the tool touched the surface at the frame's last tick
};

struct FrameStats {
    int frame = 0;   ///< from 1
    double t_s = 0.0; ///< simulated time at its end
    int level = 0;    ///< the level it was simulated at
    std::optional<LevelChange> level_change; ///< the frame began by moving to `level` (its time is in frame_ms)
    ToolsFrame tools;
    StepFigures step; ///< zero (and converged) while the object is held
    double frame_ms = 0.0; ///< the whole frame, wall clock: device ticks, tools, cuts and step
    std::vector<PatchFrame> patches; ///< per device (device runs)
};

/// A run is running away, not deforming, when its most stretched element (StepFigures::max_stretch,
/// the root mean square of its stretches) is stretched over k_runaway_stretch times its size and
/// that grows by k_runaway_growth or more in each of k_runaway_frames frames in a row: a numerical
/// divergence grows geometrically (an Is-XFEM block pinched at level 0: 5, 36, 770, 34,000 in
/// three-frame steps, on to 1e39 mm with the run ending "successfully"), while a physical blow
/// (the stability bench's 1,000 N kick on one voxel: 225 at once, then less) does not go on growing.
inline constexpr double k_runaway_stretch = 20.0;
inline constexpr double k_runaway_growth = 1.2;
inline constexpr int k_runaway_frames = 3;

/// A step whose state is no longer finite, or running away (k_runaway_stretch): what follows
/// cannot be computed (an InputError, so a command reports it as bad input; benches tell it from
/// other refusals).
class Diverged : public InputError {
public:
    using InputError::InputError;
};

class FrameLoop {
public:
    /// Keeps references to all four (`device` may be null: the tools follow the script).
    FrameLoop(const io::Scene& scene, Method& method, ToolPolicy& tools, DeviceRun* device = nullptr);

    /// The next frame. Throws Diverged when its state is no longer finite or runs away.
    FrameStats next();

    /// Frames done so far.
    [[nodiscard]] int frames() const { return m_frame; }
    /// A resumed session goes on after `frame` (its simulated time from frame * dt_s on).
    void go_on_from(int frame) { m_frame = frame; }
    /// After the method was replaced (the viewer's level keys) or restored: the loop goes on with it.
    void set_method(Method& method) { m_method = &method; }
    [[nodiscard]] Method& method() { return *m_method; }

    /// From now on the governor moves the method between levels (its decisions taken at the end
    /// of a frame, carried out at the start of the next).
    void govern_levels(LevelGovernor governor) { m_governor = std::move(governor); }
    [[nodiscard]] LevelGovernor* governor() { return m_governor ? &*m_governor : nullptr; }
    /// Moves the method to `level` now (the viewer's level keys), carrying its state: the change,
    /// or nothing when the method cannot (the reason is logged). Throws nothing.
    std::optional<LevelChange> move_to_level(int level, std::string reason);

private:
    const io::Scene& m_scene;
    Method* m_method;
    ToolPolicy& m_tools;
    DeviceRun* m_device;
    int m_frame = 0;
    std::optional<LevelGovernor> m_governor;
    std::optional<LevelChange> m_pending; ///< decided at the end of the last frame
    double m_last_stretch = 1.0;          ///< the last frame's StepFigures::max_stretch
    int m_growing = 0;                    ///< frames in a row over k_runaway_stretch, each k_runaway_growth more
};

} // namespace vox::sim
