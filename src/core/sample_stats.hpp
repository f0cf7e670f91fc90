#pragma once
// Timings and other samples summarised for people: quantiles, and the machine they were taken on.

#include <string>
#include <vector>

namespace vox {

/// The q-quantile of `values` by nearest rank (q in [0, 1]); 0 when there are none.
[[nodiscard]] double quantile(std::vector<double> values, double q);

/// "model name" of the CPU and the number of hardware threads, for benchmark reports.
[[nodiscard]] std::string machine_description();

} // namespace vox
