#pragma once
// Wall-clock phases of a computation, for the timings runs and benchmarks report.

#include <chrono>

namespace vox {

class Stopwatch {
public:
    /// Milliseconds since construction or the previous lap; starts the next lap.
    double lap()
    {
        const auto now = std::chrono::steady_clock::now();
        const double ms = std::chrono::duration<double, std::milli>(now - m_start).count();
        m_start = now;
        return ms;
    }

private:
    std::chrono::steady_clock::time_point m_start = std::chrono::steady_clock::now();
};

} // namespace vox
