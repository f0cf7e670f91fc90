#pragma once
// The simulation thread of a viewer session: takes the window's requests (tool actions, cut mode,
// levels, undo, save), puts the device's tool where the haptic thread left it, steps the frame loop
// (sim/frame_loop.hpp), publishes the surface near the tool for the haptic thread and the next
// picture for the window. It touches the method, the tools and the scene's tool settings alone.
// step() is one iteration, so a test can drive it without threads or a window.

#include "sim/frame_loop.hpp"
#include "sim/undo_history.hpp"
#include "view/view_channels.hpp"

#include <chrono>
#include <filesystem>
#include <thread>
#include <memory>

namespace vox::view {

struct ViewSimulationOptions {
    int grid_levels = 6;                ///< the coarsest level the level keys reach
    int smooth = 4;                     ///< display smoothing the window gives the surface
    std::filesystem::path out_dir = "."; ///< where S saves
    Eigen::Vector3d start_mm = Eigen::Vector3d::Zero(); ///< where the tool is until the haptic thread reports
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
    /// The device lets go of its tool (after the object changed under it).
    void let_go();
    void save() const;
    void make_picture();

    io::Scene& m_scene;
    std::unique_ptr<sim::Method> m_method;
    sim::ToolPolicy& m_tools;
    ViewChannels& m_channels;
    ViewSimulationOptions m_options;
    sim::FrameLoop m_loop;
    sim::UndoHistory m_history; ///< the state before each stroke
    int m_level = 1;
    int m_driven = -1; ///< the tool the device drives (-1: none yet)
    contact::PlacedShape m_pose;
    Eigen::Vector3d m_heading = Eigen::Vector3d::Zero();
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
