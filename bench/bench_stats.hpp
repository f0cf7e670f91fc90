#pragma once
// Repeated timings summarised as median and spread, and the machine they ran on, for the
// benchmark programs (figures go to the README).

#include "core/sample_stats.hpp"

#include <algorithm>
#include <chrono>
#include <string>
#include <vector>

namespace vox::bench {

struct Summary {
    double median = 0.0, min = 0.0, max = 0.0;
    std::size_t runs = 0;
};

inline Summary summarize(std::vector<double> samples)
{
    std::sort(samples.begin(), samples.end());
    Summary s;
    s.runs = samples.size();
    if (samples.empty()) return s;
    s.median = quantile(samples, 0.5); // the one median of every table (core/sample_stats.hpp)
    s.min = samples.front();
    s.max = samples.back();
    return s;
}

/// Wall-clock milliseconds of f().
template <class F> double time_ms(F&& f)
{
    const auto start = std::chrono::steady_clock::now();
    f();
    return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
}

/// The CPU and its hardware threads.
inline std::string machine() { return machine_description(); }

} // namespace vox::bench
