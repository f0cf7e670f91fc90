#pragma once
// voxsculpt bench tradeoff: the coarsening level's speed against its accuracy, on a cantilever
// (against Euler-Bernoulli and level 0) and the liver (against level 1).

#include <filesystem>

namespace vox::bench {

/// Writes `out`/tradeoff.md and tradeoff.svg (and prints the table); `liver`: also the liver (slow).
void run_tradeoff(const std::filesystem::path& out, bool liver);

} // namespace vox::bench
