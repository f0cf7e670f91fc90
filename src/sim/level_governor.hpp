#pragma once
// "levels": "auto" with "step_budget_ms" keeps its promise while a view or device run goes on. The
// level choice (sim/level_choice.hpp) picks the finest level whose frames fit the budget, judged on
// a few frames before the run; a user then cuts more, drills deeper or presses harder than those
// frames did. The governor watches every whole frame's wall time:
//  - coarser: when the frames of about the last second (k_judge_s of wall time) miss the budget
//    (their 90th percentile, the choice's own measure, above it), the run moves one level
//    coarser, carrying its state (Method::move_to_level);
//  - finer: when the frames of the last k_room_s would fit one level finer (their 90th percentile,
//    scaled by how much slower the choice measured that level, under k_room_share of the budget),
//    and k_settle_s have passed since it moved coarser, it moves back, never finer than the level
//    the choice picked (or the user's level keys set).
// Frames right after a move (k_warm_up_frames: the new level's factor, its first contact) are not
// judged. The governor only decides; the frame loop moves the method and records why.

#include "io/scene.hpp"

#include <map>
#include <optional>
#include <string>
#include <vector>

namespace vox::sim {

struct LevelChoice;

/// A move between levels, as stats.json and recordings hold it.
struct LevelChange {
    int from = 0, to = 0;
    std::string reason; ///< why, in words ("frames over budget: 90th percentile 23.4 ms > 16 ms over 1.0 s")
    double ms = 0.0;    ///< what the move itself took (model, solver and state carried over)
};

class LevelGovernor {
public:
    inline static constexpr double k_judge_s = 1.0;
    inline static constexpr double k_room_s = 2.0;
    inline static constexpr double k_room_share = 0.8;
    inline static constexpr double k_settle_s = 3.0;
    inline static constexpr int k_warm_up_frames = 2;

    struct Settings {
        double budget_ms = 16.0;
        double dt_s = 0.01; ///< a frame takes at least this much wall time in a paced run
        int finest = 1;     ///< never finer than this
        int coarsest = 6;   ///< never coarser than this
        /// Per level: its frames' 90th percentile as the choice measured it, and the fastest
        /// preconditioner there (levels the choice did not measure: neither).
        std::map<int, double> measured_ms;
        std::map<int, io::PreconditionerChoice> preconditioner;
        io::PreconditionerChoice scene_preconditioner = io::PreconditionerChoice::automatic;
        std::vector<int> unusable; ///< levels the object cannot be simulated at: never tried
    };

    explicit LevelGovernor(Settings settings);

    /// After a frame at `level` that took `frame_ms` of wall time: the level to move to and why.
    [[nodiscard]] std::optional<LevelChange> after_frame(int level, double frame_ms);
    /// The preconditioner to move to `level` with.
    [[nodiscard]] io::PreconditionerChoice preconditioner(int level) const;
    /// The run is now at `level` (moved, by the governor or the user's keys): the windows restart.
    void moved(int from, int to);
    /// Moving to `level` failed (the object cannot be simulated there): it is not tried again.
    void refused(int level);
    /// The user's level keys chose `level`: it becomes the finest the governor returns to.
    void set_finest(int level);
    [[nodiscard]] const Settings& settings() const { return m_settings; }

private:
    /// The 90th percentile of the frames of the last `seconds` of wall time, or nothing when the
    /// judged frames do not yet span that long.
    [[nodiscard]] std::optional<double> recent_p90(double seconds) const;

    Settings m_settings;
    std::vector<double> m_frames_ms; ///< judged frames since the last move, wall time each
    int m_skip = 0;                  ///< frames still to skip after a move
    double m_since_coarser_s = 1e9;  ///< wall time since the last move coarser
    std::vector<int> m_refused;
};

/// The governor of a budget run ("levels": "auto" with "step_budget_ms"), from what the level
/// choice measured; nothing for other scenes (a fixed level, or "max_error").
[[nodiscard]] std::optional<LevelGovernor> level_governor(const io::Scene& scene, const LevelChoice& choice, int coarsest_level);

} // namespace vox::sim
