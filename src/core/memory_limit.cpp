#include "core/memory_limit.hpp"

#include "core/error.hpp"

#include <atomic>
#include <cstdlib>
#include <limits>

namespace vox {
namespace {
std::uint64_t initial_limit()
{
    if (const char* env = std::getenv("VOXSCULPT_MAX_MEMORY_MB")) {
        char* end = nullptr;
        const unsigned long long mb = std::strtoull(env, &end, 10);
        if (end != env && *end == '\0' && mb > 0) return static_cast<std::uint64_t>(mb) << 20;
    }
    return std::uint64_t{8} << 30;
}
std::atomic<std::uint64_t> g_limit{initial_limit()};
} // namespace

std::uint64_t memory_limit_bytes() { return g_limit.load(); }

void check_memory_limit_environment()
{
    const char* env = std::getenv("VOXSCULPT_MAX_MEMORY_MB");
    if (!env) return;
    char* end = nullptr;
    const unsigned long long mb = std::strtoull(env, &end, 10);
    if (end == env || *end != '\0' || mb == 0 || env[0] == '-')
        throw InputError(std::string("VOXSCULPT_MAX_MEMORY_MB=") + env + ": not a positive whole number of MiB");
}
void set_memory_limit_bytes(std::uint64_t bytes) { g_limit = bytes; }

void check_allocation(const std::string& what, std::uint64_t count, std::uint64_t bytes_each)
{
    const std::uint64_t limit = memory_limit_bytes();
    if (bytes_each != 0 && count > std::numeric_limits<std::uint64_t>::max() / bytes_each)
        throw file_error(what, "dimensions overflow 64-bit sizes");
    const std::uint64_t need = count * bytes_each;
    if (need > limit)
        throw file_error(what, "would need " + std::to_string(need >> 20) + " MiB, more than the memory limit of " +
                                   std::to_string(limit >> 20) + " MiB (set --max-memory-mb to raise it)");
}

} // namespace vox
