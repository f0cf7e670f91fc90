#pragma once
// The process's peak resident memory, for build reports and benchmarks.

#include <cstdint>

namespace vox {

/// Peak resident set size of this process so far, bytes (getrusage).
[[nodiscard]] std::uint64_t peak_memory_bytes();

} // namespace vox
