#include "io/tool_script.hpp"

#include <stdexcept>
#include <string>

namespace vox::io {

ToolPose tool_pose(const Scene& scene, std::size_t tool_index, double t_s)
{
    if (tool_index >= scene.tools.size()) {
        throw std::out_of_range("tool_pose: tool index " + std::to_string(tool_index) + " out of range (" +
                                std::to_string(scene.tools.size()) + " tools)");
    }
    // The script is in time order. `before`: the last entry at or before t_s, so of two entries at
    // one time the later wins from that time on; `after`: the first entry at or after t_s.
    const ScriptEntry* before = nullptr;
    const ScriptEntry* after = nullptr;
    for (const ScriptEntry& e : scene.script) {
        if (e.tool_index != tool_index) {
            continue;
        }
        if (e.t_s <= t_s) {
            before = &e;
        }
        if (e.t_s >= t_s && after == nullptr) {
            after = &e;
        }
    }
    ToolPose pose;
    if (before != nullptr && after != nullptr && after->t_s > before->t_s) {
        const double a = (t_s - before->t_s) / (after->t_s - before->t_s);
        pose.placed = true;
        pose.position_mm = (1 - a) * before->position_mm + a * after->position_mm;
        // Eigen's slerp takes the shorter way (q and -q are the same rotation).
        pose.orientation = before->orientation.slerp(a, after->orientation).normalized();
    } else if (before != nullptr || after != nullptr) {
        const ScriptEntry& e = before != nullptr ? *before : *after;
        pose.placed = true;
        pose.position_mm = e.position_mm;
        pose.orientation = e.orientation;
    }
    return pose;
}

} // namespace vox::io
