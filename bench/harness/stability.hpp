#pragma once
// voxsculpt bench stability: the solver at the extremes. Each case runs a scene for a number of
// steps and is judged: "stable" (everything finite, displacements bounded, motion dying out),
// "refused" (the scene reader or solver turned it down with a message), or "diverged"
// (non-finite numbers, runaway displacement or energy). Never NaN, never a silent explosion.

#include <filesystem>
#include <string>
#include <vector>

namespace vox::bench {

struct StabilityResult {
    std::string object, variation, outcome, detail;
    int steps = 0;
    double max_displacement_mm = 0.0, max_stretch = 1.0, final_kinetic_j = 0.0, peak_kinetic_j = 0.0, final_elastic_j = 0.0;
    int unconverged_steps = 0;
    int projected_steps = 0; ///< steps whose created energy was taken out again (fem::StepStats::energy_projected)
};

/// Runs the sweep (beam and, unless `quick`, liver) and returns every case's result.
[[nodiscard]] std::vector<StabilityResult> run_stability(bool quick);

/// Writes DIR/stability.md (a table) and DIR/stability.json.
void write_stability(const std::filesystem::path& dir, const std::vector<StabilityResult>& results);

} // namespace vox::bench
