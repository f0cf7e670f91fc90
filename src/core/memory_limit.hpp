#pragma once
// A configurable ceiling on what one reader may allocate, checked against header dimensions
// before any allocation so a corrupt or hostile header cannot exhaust memory.

#include <cstdint>
#include <string>

namespace vox {

/// Default 8 GiB; overridden by the environment variable VOXSCULPT_MAX_MEMORY_MB or the
/// program's --max-memory-mb option.
[[nodiscard]] std::uint64_t memory_limit_bytes();
/// Throws InputError when VOXSCULPT_MAX_MEMORY_MB is set but is not a positive whole number.
void check_memory_limit_environment();
void set_memory_limit_bytes(std::uint64_t bytes);

/// Throws InputError naming `what` (usually the file) when `count * bytes_each` exceeds the limit
/// or overflows 64 bits.
void check_allocation(const std::string& what, std::uint64_t count, std::uint64_t bytes_each);

} // namespace vox
