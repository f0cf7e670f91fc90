#pragma once
// What every `voxsculpt run` writes the same way, whichever solver ran: frame file names, the
// tools of a frame and the step totals of stats.json's summary.

#include "app/tool_session.hpp"

#include <nlohmann/json.hpp>

#include <cstdio>
#include <string>

namespace vox::app {

/// "frame_NNNNN.EXT" (frame numbers from 1).
inline std::string frame_file_name(int frame, const char* extension)
{
    char name[48];
    std::snprintf(name, sizeof name, "frame_%05d.%s", frame, extension);
    return name;
}

/// The summary's step totals: frames, total, mean and max step time (ms), converged frames.
inline nlohmann::json step_summary(int frames, double total_ms, double max_ms, int converged)
{
    return {{"frames", frames},
            {"total_step_ms", total_ms},
            {"mean_step_ms", frames ? total_ms / frames : 0.0},
            {"max_step_ms", max_ms},
            {"converged_frames", converged}};
}

/// A frame's tools for stats.json: null for a tool not placed.
inline nlohmann::json tool_frames_json(const std::vector<ToolFrame>& tools)
{
    nlohmann::json out = nlohmann::json::array();
    for (const ToolFrame& t : tools) {
        if (!t.placed) {
            out.push_back(nullptr);
            continue;
        }
        out.push_back({{"position_mm", {t.position_mm.x(), t.position_mm.y(), t.position_mm.z()}},
                       {"force_n", {t.force_n.x(), t.force_n.y(), t.force_n.z()}},
                       {"torque_n_mm", {t.torque_n_mm.x(), t.torque_n_mm.y(), t.torque_n_mm.z()}},
                       {"pressure_pa", t.pressure_pa},
                       {"contact_area_mm2", t.contact_area_mm2},
                       {"cut", t.cut}});
    }
    return out;
}

} // namespace vox::app
