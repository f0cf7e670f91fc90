#include "sim/frame_loop.hpp"

#include "core/error.hpp"
#include "core/log.hpp"
#include "core/stopwatch.hpp"
#include "sim/device_run.hpp"

#include <spdlog/fmt/fmt.h>

#include <algorithm>
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
    // A replay goes where the recording went; a live run where the governor decided.
    if (const std::optional<int> recorded = m_device ? m_device->recorded_level((m_frame - 1) * dt) : std::nullopt;
        recorded && *recorded != m_method->level()) {
        out.level_change = move_to_level(*recorded, "as recorded: " + m_device->recorded_reason((m_frame - 1) * dt));
    } else if (m_pending) {
        out.level_change = move_to_level(m_pending->to, m_pending->reason);
    }
    m_pending.reset();
    out.level = m_method->level();
    if (m_device) {
        m_device->frame(*m_method, m_tools, (m_frame - 1) * dt, dt);
        out.patches = m_device->patches();
    }
    out.tools = m_tools.frame(*m_method, out.t_s, dt);
    if (!out.tools.hold_object) out.step = m_method->step(); // held: a two-phase cut is being marked
    // The surface's displacement, not the nodes': a corner of a nearly empty element lies up to a
    // cell outside the material, and its motion says nothing of the object's.
    for (const Eigen::Vector3d& d : m_method->surface_displacements_mm())
        out.step.max_displacement_mm = std::max(out.step.max_displacement_mm, d.norm());
    const StepFigures& s = out.step;
    if (!std::isfinite(s.kinetic_energy_j) || (s.elastic_energy_j && !std::isfinite(*s.elastic_energy_j)) || !std::isfinite(s.max_stretch))
        throw Diverged(m_scene.source + ": the simulation diverged at frame " + std::to_string(m_frame) +
                         " (non-finite state); reduce solver.dt_s or check the materials");
    m_growing = s.max_stretch > k_runaway_stretch && s.max_stretch >= k_runaway_growth * m_last_stretch ? m_growing + 1 : 0;
    m_last_stretch = s.max_stretch;
    if (m_growing >= k_runaway_frames) {
        const auto& at = s.most_stretched_mm;
        throw Diverged(fmt::format("{}: the simulation diverged at frame {}: the element at ({:.1f}, {:.1f}, {:.1f}) mm is stretched "
                                   "{:.3g} times its size, more each frame{}; reduce solver.dt_s, choose another level or check the materials and "
                                   "what holds the object",
                                   m_scene.source, m_frame, at[0], at[1], at[2], s.max_stretch,
                                   s.converged ? "" : fmt::format(" (the step did not converge: residual {:.2g})", s.residual)));
    }
    out.frame_ms = clock.lap();
    if (m_governor && !(m_device && m_device->replaying())) m_pending = m_governor->after_frame(out.level, out.frame_ms);
    return out;
}

std::optional<LevelChange> FrameLoop::move_to_level(int level, std::string reason)
{
    const int from = m_method->level();
    if (level == from) return std::nullopt;
    Stopwatch clock;
    const io::PreconditionerChoice preconditioner = m_governor ? m_governor->preconditioner(level) : m_scene.solver.preconditioner;
    try {
        if (!m_method->move_to_level(level, preconditioner)) {
            log::warn("level {}: the {} method cannot move there with its state", level, m_method->name());
            if (m_governor) m_governor->refused(level);
            return std::nullopt;
        }
    } catch (const InputError& e) {
        log::warn("level {}: not moved there: {}", level, e.what());
        if (m_governor) m_governor->refused(level);
        return std::nullopt;
    }
    LevelChange change{from, level, std::move(reason), clock.lap()};
    if (m_governor) m_governor->moved(from, level);
    if (m_device) m_device->level_changed(change);
    log::info("frame {}: level {} -> {} ({} elements, {:.0f} ms to move): {}", m_frame, from, level, m_method->element_count(), change.ms,
              change.reason);
    return change;
}

} // namespace vox::sim
