#pragma once
// voxsculpt bench compare SCENE.json: the same scene, tool script and level simulated by the
// dynamic branched grid ("dbg"), by Is-XFEM with k = 0.1 and with k = 0 (standard XFEM), and by
// shape matching on the branched grid, side by side, every column by the same code: degrees of freedom, step time, CG iterations, cut-update time, volume lost, surface
// triangles, whether every step converged, and how far the final surfaces lie apart.

#include <filesystem>
#include <optional>
#include <string>

namespace vox::bench {

/// Prints the comparison as Markdown and writes it to DIR/compare-SCENE.md.
void run_compare(const std::string& scene_path, std::optional<int> frames, const std::filesystem::path& out);

} // namespace vox::bench
