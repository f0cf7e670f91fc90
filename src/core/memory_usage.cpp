#include "core/memory_usage.hpp"

#include <sys/resource.h>

namespace vox {

std::uint64_t peak_memory_bytes()
{
    rusage usage{};
    getrusage(RUSAGE_SELF, &usage);
    return static_cast<std::uint64_t>(usage.ru_maxrss) * 1024u; // Linux reports kilobytes
}

} // namespace vox
