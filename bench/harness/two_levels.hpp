#pragma once
// voxsculpt bench levels: two levels in one model ("levels": {"fine", "coarse",
// "fine_radius_mm"}) against the uniform fine and the uniform coarse level, side by side in one
// run (see two_levels.cpp).

#include <filesystem>

namespace vox::bench {

/// Writes `out`/levels.md, levels.json, levels_force.svg and levels_surface.svg (and prints the
/// tables); `liver`: also the liver cases (minutes: the uniform level 2 takes seconds a frame).
void run_two_levels_bench(const std::filesystem::path& out, bool liver);

} // namespace vox::bench
