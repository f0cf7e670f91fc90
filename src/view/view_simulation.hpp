#pragma once
// The simulation thread of a viewer session: takes the window's requests (tool actions, cut mode,
// levels, undo, save), puts each device's tool where the haptic thread left it, steps the frame
// loop (sim/frame_loop.hpp), publishes the surface near each device's tool and its own clock for
// the haptic thread and the next picture for the window. It touches the method, the tools and the scene's tool settings alone.
// step() is one iteration, so a test can drive it without threads or a window.

#include "haptics/device.hpp"
#include "sim/frame_loop.hpp"
#include "sim/journal.hpp"
#include "sim/undo_history.hpp"
#include "view/view_channels.hpp"

#include <chrono>
#include <filesystem>
#include <thread>
#include <memory>
#include <optional>

namespace vox::view {

/// One device of the session, as the simulation sees it.
struct ViewHand {
    std::size_t tool = 0;     ///< the tool it starts on (one device: TAB moves it; several: fixed)
    Eigen::Vector3d start_mm = Eigen::Vector3d::Zero(); ///< where its tool is until the haptic thread reports
    std::string device;       ///< its name, for the window's status line
    /// The device itself, whose faults the window shows and which is asked to come back from
    /// them (null: none to watch; tests).
    haptics::Device* watched = nullptr;
    bool arms = false;        ///< its second button switches the tool's action on while held (force-feedback devices)
};

struct ViewSimulationOptions {
    int grid_levels = 6;                ///< the coarsest level the level keys reach
    int smooth = 4;                     ///< display smoothing the window gives the surface
    std::filesystem::path out_dir = "."; ///< where S saves
    /// One per device, in the order of the channels' hands.
    std::vector<ViewHand> hands = {ViewHand{}};
    /// The session journal (sim/journal.hpp): written here, for the scene file `scene_file`; empty:
    /// none (tests).
    std::filesystem::path journal;
    std::filesystem::path scene_file;
    /// An earlier session's journal of this scene, offered until the first cut: J resumes it.
    std::optional<sim::Journal> offered;
    /// "levels": "auto" with a budget: moves the session between levels as its frames take
    /// (sim/level_governor.hpp).
    std::optional<sim::LevelGovernor> governor;
};

class ViewSimulation {
public:
    /// Keeps references to `scene` (its tool settings change with the keys), `tools` and `channels`.
    ViewSimulation(io::Scene& scene, std::unique_ptr<sim::Method> method, sim::ToolPolicy& tools, ViewChannels& channels,
                   const ViewSimulationOptions& options);

    /// One iteration at wall time `now_s`: the requests, then (unless paused) one frame, the
    /// snapshot and, when the window has taken the last one, the next picture. False when paused
    /// (no frame was stepped).
    bool step(double now_s);
    /// Steps until channels.requests.stop, simulated time paced to wall time; a late frame does
    /// not wait. `now_s` gives the session's wall time.
    template <class Clock> void run(Clock now_s);

    [[nodiscard]] const sim::Method& method() const { return *m_method; }
    [[nodiscard]] int level() const { return m_level; }
    [[nodiscard]] const sim::UndoHistory& history() const { return m_history; }

private:
    void take_requests();
    /// The devices let go of their tools (after the object changed under them).
    void let_go();
    void save() const;
    void make_picture();
    /// A new journal for the method as it now is (the session's start, another level).
    void start_journal();
    /// The session is now at the method's level (moved by the keys or the governor).
    void now_at_level(const std::string& why);
    /// The earlier session's cuts made on the object, when it has none yet.
    void resume_offered();
    /// Devices that fault: said on screen and in the log, and asked to come back.
    void watch_faults();

    io::Scene& m_scene;
    std::unique_ptr<sim::Method> m_method;
    sim::ToolPolicy& m_tools;
    ViewChannels& m_channels;
    ViewSimulationOptions m_options;
    sim::FrameLoop m_loop;
    sim::UndoHistory m_history; ///< the state before each stroke
    std::unique_ptr<sim::JournalWriter> m_journal;
    sim::StrokeEnds m_stroke_ends; ///< a 6-DoF controller's strokes (no button says when they end)
    int m_level = 1;
    std::string m_level_notice; ///< the last move between levels, shown for a few seconds
    std::string m_fault_notice; ///< a device that does not answer, shown while it does not
    double m_level_notice_until_s = 0.0;
    double m_now_s = 0.0;
    /// Per device: the tool it drives (-1: none yet), where the haptic thread put it and where
    /// the device is heading.
    struct Hand {
        int driven = -1;
        contact::PlacedShape pose;
        Eigen::Vector3d heading = Eigen::Vector3d::Zero(); ///< the driver
        double coupling_n_per_mm = 0.0;                     ///< the spring between it and the tool
    };
    std::vector<Hand> m_hands;
};

template <class Clock> void ViewSimulation::run(Clock now_s)
{
    const double dt = m_scene.solver.dt_s;
    double next = now_s();
    while (!m_channels.requests.stop.load()) {
        if (!step(now_s())) {
            std::this_thread::sleep_for(std::chrono::milliseconds(5));
            next = now_s();
            continue;
        }
        next += dt;
        const double wait = next - now_s();
        if (wait > 0.0) std::this_thread::sleep_for(std::chrono::duration<double>(wait));
        else next = now_s();
    }
}

} // namespace vox::view
