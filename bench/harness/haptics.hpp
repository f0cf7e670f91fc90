#pragma once
// voxsculpt bench haptics (see bench_haptics.cpp).

namespace vox::bench {

/// Runs the 1 kHz loop for `seconds` beside the press-and-cut simulation (the branched grid, or
/// Is-XFEM with `isxfem`) and prints its timing table.
void run_haptics_bench(double seconds, bool isxfem = false);

} // namespace vox::bench
