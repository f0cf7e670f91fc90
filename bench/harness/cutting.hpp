#pragma once
// voxsculpt bench cutting (see bench_cutting.cpp).

namespace vox::bench {

/// Runs the liver incision `runs` times and prints the cutting-frame timings.
void run_cutting_bench(int runs);

} // namespace vox::bench
