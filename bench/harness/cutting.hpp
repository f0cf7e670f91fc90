#pragma once
// voxsculpt bench cutting (see cutting.cpp).

#include <filesystem>

namespace vox::bench {

/// Runs the liver incision `runs` times with each preconditioner and writes cutting.md and
/// cutting.json into `dir`.
void run_cutting_bench(int runs, const std::filesystem::path& dir);

} // namespace vox::bench
