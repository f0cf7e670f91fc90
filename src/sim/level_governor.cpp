#include "sim/level_governor.hpp"

#include "core/sample_stats.hpp"
#include "sim/level_choice.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>

namespace vox::sim {
namespace {

/// How much slower a level is than the next coarser one when the choice did not measure it: the
/// degrees of freedom grow about fourfold per level on a shell, eightfold on a solid.
constexpr double k_unmeasured_ratio = 4.0;

std::string ms_text(double ms)
{
    char text[32];
    std::snprintf(text, sizeof text, "%.1f ms", ms);
    return text;
}

} // namespace

LevelGovernor::LevelGovernor(Settings settings) : m_settings(std::move(settings)), m_refused(m_settings.unusable) {}

io::PreconditionerChoice LevelGovernor::preconditioner(int level) const
{
    // The scene's own choice wins; under "auto", what the choice measured fastest there.
    if (m_settings.scene_preconditioner != io::PreconditionerChoice::automatic) return m_settings.scene_preconditioner;
    const auto p = m_settings.preconditioner.find(level);
    return p == m_settings.preconditioner.end() ? io::PreconditionerChoice::automatic : p->second;
}

std::optional<double> LevelGovernor::recent_p90(double seconds) const
{
    double wall_ms = 0.0;
    std::vector<double> recent;
    for (auto f = m_frames_ms.rbegin(); f != m_frames_ms.rend() && wall_ms < 1e3 * seconds; ++f) {
        recent.push_back(*f);
        wall_ms += std::max(*f, 1e3 * m_settings.dt_s);
    }
    if (wall_ms < 1e3 * seconds) return std::nullopt;
    return quantile(std::move(recent), 0.9);
}

std::optional<LevelChange> LevelGovernor::after_frame(int level, double frame_ms)
{
    m_since_coarser_s += std::max(frame_ms, 1e3 * m_settings.dt_s) * 1e-3;
    if (m_skip > 0) {
        --m_skip;
        return std::nullopt;
    }
    m_frames_ms.push_back(frame_ms);
    // The longest window looked at holds at most k_room_s / dt frames: older ones are dropped.
    if (const auto keep = static_cast<std::size_t>(std::ceil(k_room_s / m_settings.dt_s)) + 1; m_frames_ms.size() > 2 * keep)
        m_frames_ms.erase(m_frames_ms.begin(), m_frames_ms.end() - static_cast<std::ptrdiff_t>(keep));
    const auto usable = [&](int l) { return std::find(m_refused.begin(), m_refused.end(), l) == m_refused.end(); };
    const double budget = m_settings.budget_ms;
    if (const auto p90 = recent_p90(k_judge_s); p90 && *p90 > budget) {
        for (int to = level + 1; to <= m_settings.coarsest; ++to)
            if (usable(to))
                return LevelChange{level, to,
                                   "frames over budget: 90th percentile " + ms_text(*p90) + " > " + ms_text(budget) + " over the last second",
                                   0.0};
        return std::nullopt; // the coarsest usable level: nothing cheaper to move to
    }
    if (level <= m_settings.finest || m_since_coarser_s < k_settle_s) return std::nullopt;
    int to = level - 1;
    while (to >= m_settings.finest && !usable(to)) --to;
    if (to < m_settings.finest) return std::nullopt;
    const auto p90 = recent_p90(k_room_s);
    if (!p90) return std::nullopt;
    const auto here = m_settings.measured_ms.find(level), there = m_settings.measured_ms.find(to);
    double ratio = 1.0;
    for (int l = to; l < level; ++l) ratio *= k_unmeasured_ratio;
    if (here != m_settings.measured_ms.end() && there != m_settings.measured_ms.end() && here->second > 0.0)
        ratio = std::max(1.0, there->second / here->second);
    const double expected = *p90 * ratio;
    if (expected > k_room_share * budget) return std::nullopt;
    return LevelChange{level, to,
                       "room in the budget: 90th percentile " + ms_text(*p90) + " over the last 2 s, about " + ms_text(expected) +
                           " at level " + std::to_string(to) + " (within 80 % of " + ms_text(budget) + ")",
                       0.0};
}

void LevelGovernor::moved(int from, int to)
{
    m_frames_ms.clear();
    m_skip = k_warm_up_frames;
    if (to > from) m_since_coarser_s = 0.0;
}

void LevelGovernor::refused(int level)
{
    m_refused.push_back(level);
    m_frames_ms.clear();
}

void LevelGovernor::set_finest(int level)
{
    m_settings.finest = level;
    m_frames_ms.clear();
    m_skip = k_warm_up_frames;
}

std::optional<LevelGovernor> level_governor(const io::Scene& scene, const LevelChoice& choice, int coarsest_level)
{
    if (!scene.object.auto_levels || !scene.object.step_budget_ms) return std::nullopt;
    LevelGovernor::Settings s;
    s.budget_ms = *scene.object.step_budget_ms;
    s.dt_s = scene.solver.dt_s;
    s.finest = choice.level;
    s.coarsest = std::max(coarsest_level, choice.level);
    s.scene_preconditioner = scene.solver.preconditioner;
    s.unusable = choice.unusable;
    for (const LevelTrial& t : choice.trials) {
        s.measured_ms[t.level] = t.frame_ms;
        s.preconditioner[t.level] = t.preconditioner;
    }
    return LevelGovernor(std::move(s));
}

} // namespace vox::sim
