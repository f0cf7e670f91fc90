#pragma once
// voxsculpt bench drilling (see drilling.cpp).

#include <filesystem>

namespace vox::bench {

/// Drills the burr hole of data/scenes/skull_burr_hole.json with the skull elastic and rigid, each
/// `runs` times with "levels": "auto" and a 16 ms budget, and writes drilling.md and drilling.json
/// into `dir`.
void run_drilling_bench(int runs, const std::filesystem::path& dir);

} // namespace vox::bench
