#pragma once
// A scripted device in a live session (the viewer, a run with a force-feedback device): it
// follows the scene's script for its tool in simulated time, not wall time, so that it waits
// while the simulation is paused or falls behind, as the tool it drives does. The simulation publishes the time of each frame; between two frames the device
// runs on with the loop's clock, at most one frame ahead, so its tool glides rather than jumping
// once a frame.

#include "haptics/virtual_device.hpp"

#include <algorithm>
#include <atomic>
#include <string>
#include <utility>

namespace vox::haptics {

class PacedDevice final : public Device {
public:
    /// `simulation_t_s`: the simulated time of the last frame; `frame_s`: the simulation's step.
    PacedDevice(std::vector<KeyFrame> frames, const std::atomic<double>& simulation_t_s, double frame_s)
        : m_script(std::move(frames)), m_simulation_t_s(simulation_t_s), m_frame_s(frame_s)
    {
    }
    [[nodiscard]] std::string name() const override { return "script"; }
    [[nodiscard]] const DeviceLimits& limits() const override { return m_script.limits(); }
    bool read(double t_s, DeviceState& state) noexcept override
    {
        const double frame = m_simulation_t_s.load(std::memory_order_relaxed);
        if (frame != m_frame) { // a new frame: run on from it
            m_frame = frame;
            m_frame_seen_s = t_s;
        }
        const bool fresh = m_script.read(m_frame + std::clamp(t_s - m_frame_seen_s, 0.0, m_frame_s), state);
        state.t_s = t_s;
        return fresh;
    }

private:
    VirtualDevice m_script;
    const std::atomic<double>& m_simulation_t_s;
    double m_frame_s;
    double m_frame = -1.0, m_frame_seen_s = 0.0;
};

} // namespace vox::haptics
