#pragma once
// voxsculpt bench haptics (see bench_haptics.cpp).

namespace vox::app {

/// Runs the 1 kHz loop for `seconds` beside the liver simulation and prints its timing table.
void run_haptics_bench(double seconds);

} // namespace vox::app
