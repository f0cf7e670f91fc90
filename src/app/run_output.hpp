#pragma once
// What every `voxsculpt run` writes the same way, whichever solver ran: frame file names and the
// step totals of stats.json's summary.

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

} // namespace vox::app
