#pragma once
// A progress bar on stderr for long work: silent unless stderr is a terminal, the logger is not
// quiet, and the work has already taken about a second (short work prints nothing).

#include <chrono>
#include <cstdint>
#include <string>

namespace vox {

class Progress {
public:
    /// `label` names the work ("reading liver.inr.gz"); `total` is the number of steps.
    Progress(std::string label, std::uint64_t total);
    ~Progress();
    Progress(const Progress&) = delete;
    Progress& operator=(const Progress&) = delete;

    /// Reports that `done` of `total` steps are finished. Cheap to call often (redraws <= 10 Hz).
    void update(std::uint64_t done);
    /// Clears the bar's line (also done by the destructor).
    void finish();

private:
    std::string m_label;
    std::uint64_t m_total;
    bool m_enabled;
    bool m_drawn = false;
    std::chrono::steady_clock::time_point m_start;
    std::chrono::steady_clock::time_point m_last_draw;
};

} // namespace vox
