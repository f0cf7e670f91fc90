#pragma once
// What every fuzz target shares: the fuzzer's bytes as a file (the readers take paths, as the
// program does), the limits fuzzed input runs under, and the one rule a reader must keep: bad
// input is refused with an InputError. Any other exception, a crash or a sanitizer report is a bug.

#include "core/error.hpp"

#include <cstddef>
#include <cstdint>
#include <string>

namespace vox::fuzz {

/// Writes the input to this process's scratch file named `name` (its extension picks the format)
/// and returns the path. The same path on every call: a target reads one input at a time.
[[nodiscard]] std::string input_file(const std::uint8_t* data, std::size_t size, const std::string& name);

/// True when the input starts with the gzip magic (1f 8b): the file then gets a ".gz" name, as
/// a user's would.
[[nodiscard]] bool is_gzip(const std::uint8_t* data, std::size_t size);

/// Once per process: a memory limit of 256 MiB (so a header asking for gigabytes is refused, as
/// in the program) and only errors logged.
void setup();

/// How many inputs were refused so far, and the last refusal (the replay reports them: a seed must
/// be accepted).
[[nodiscard]] std::size_t& refused_count();
[[nodiscard]] std::string& last_refusal();

/// Runs `read`, accepting an InputError as the refusal every reader promises.
template <class Read> int read_or_refuse(Read&& read)
{
    setup();
    try {
        read();
    } catch (const InputError& e) {
        ++refused_count();
        last_refusal() = e.what();
    }
    return 0;
}

} // namespace vox::fuzz
