#pragma once
// stats.json of a run, written the same way whichever method ran: per frame the step, the cut's
// phases and counts, and the tools; a summary at the end. The branched grid's keys are the shared
// names (scripts read them); figures only one method has go under its own key ("isxfem": {...}).
// docs/scene-format.md lists them.

#include "sim/frame_loop.hpp"

#include <nlohmann/json.hpp>

#include <map>
#include <string>
#include <vector>

namespace vox::sim {

/// "frame_NNNNN.EXT" (frame numbers from 1).
[[nodiscard]] std::string frame_file_name(int frame, const char* extension);

/// A frame's tools for stats.json: null for a tool not placed.
[[nodiscard]] nlohmann::json tool_frames_json(const std::vector<ToolFrame>& tools);

class RunRecord {
public:
    /// The run's header: the scene file as given, the method and its model.
    RunRecord(const std::string& scene_path, const Method& method, double dt_s);

    /// Appends one frame.
    void add(const FrameStats& frame, const Method& method);
    /// The summary after the last frame; the document is then complete.
    void finish(const Method& method);

    [[nodiscard]] nlohmann::json& document() { return m_document; }
    [[nodiscard]] const nlohmann::json& document() const { return m_document; }
    [[nodiscard]] double total_step_ms() const { return m_total_ms; }
    [[nodiscard]] const StepFigures& last_step() const { return m_last; }
    /// The tools that asked for a contact patch (haptic_subdivision) and touched the surface,
    /// and how many frames they touched it in, but were given none in any of them.
    [[nodiscard]] std::vector<std::pair<std::string, std::size_t>> tools_given_no_patch() const;

private:
    nlohmann::json m_document;
    int m_frames = 0, m_converged = 0;
    double m_total_ms = 0.0, m_max_ms = 0.0;
    std::size_t m_removed = 0, m_separated_faces = 0, m_separated_voxels = 0;
    std::size_t m_projected = 0;      ///< frames whose step lost the energy it created (StepFigures::energy_projected)
    std::size_t m_recovered = 0;      ///< frames whose refused first solve a fuller one replaced (StepFigures::recovered)
    std::size_t m_fallbacks = 0;      ///< frames in which a preconditioner failed
    std::size_t m_inverted_frames = 0; ///< frames ending with an inverted element (StepFigures::inverted_elements)
    double m_max_stretch = 1.0;        ///< the largest StepFigures::max_stretch of any frame
    std::vector<double> m_frame_ms;   ///< whole frames, wall clock
    std::vector<double> m_cutting_ms; ///< frames that cut: collision + propagation + grid update + remesh
    std::size_t m_patch_frames = 0;   ///< device frames with a contact patch (per device)
    /// Per tool that asks for a patch: the frames it touched in, and those it had a patch in.
    std::map<std::string, std::pair<std::size_t, std::size_t>> m_patch_use;
    StepFigures m_last;
};

} // namespace vox::sim
