#include "sim/frame_loop.hpp"

#include "core/error.hpp"
#include "core/stopwatch.hpp"
#include "sim/device_run.hpp"

#include <cmath>

namespace vox::sim {

FrameLoop::FrameLoop(const io::Scene& scene, Method& method, ToolPolicy& tools, DeviceRun* device)
    : m_scene(scene), m_method(&method), m_tools(tools), m_device(device)
{
}

FrameStats FrameLoop::next()
{
    Stopwatch clock;
    const double dt = m_scene.solver.dt_s;
    FrameStats out;
    out.frame = ++m_frame;
    out.t_s = m_frame * dt;
    if (m_device) m_device->frame(*m_method, m_tools, (m_frame - 1) * dt, dt);
    out.tools = m_tools.frame(*m_method, out.t_s, dt);
    if (!out.tools.hold_object) out.step = m_method->step(); // held: a two-phase cut is being marked
    const StepFigures& s = out.step;
    if (!std::isfinite(s.kinetic_energy_j) || (s.elastic_energy_j && !std::isfinite(*s.elastic_energy_j)))
        throw Diverged(m_scene.source + ": the simulation diverged at frame " + std::to_string(m_frame) +
                         " (non-finite energy); reduce solver.dt_s or check the materials");
    out.frame_ms = clock.lap();
    return out;
}

} // namespace vox::sim
