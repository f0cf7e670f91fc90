#pragma once
// Running untrusted parsing where it cannot hurt the program: a forked child process with a
// ceiling on the memory it may add and on its wall time. Used for readers of libraries that trust
// the counts in a file (OpenVDB's): a corrupt file then costs a message, not a crash, a hang or
// gigabytes.

#include <cstdint>
#include <functional>
#include <string>

namespace vox {

/// How a child ended.
struct ChildOutcome {
    enum class Kind {
        ok,            ///< `work` returned
        failed,        ///< `work` threw; `message` holds what() (at most 1000 bytes)
        out_of_memory, ///< `work` needed more memory than allowed (std::bad_alloc)
        timed_out,     ///< killed after the time allowed
        crashed,       ///< killed by a signal of its own (SIGSEGV, SIGABRT...); `signal` says which
    };
    Kind kind = Kind::ok;
    std::string message;
    int signal = 0;
};

/// Limits for run_in_child.
struct ChildLimits {
    std::uint64_t memory_bytes = 0; ///< address space the child may add to what it starts with
    double seconds = 0.0;           ///< wall time before it is killed
    bool silence_stderr = true;     ///< the library's own warnings would add lines to our one-line errors
};

/// Runs `work` in a child made with fork(): it sees the caller's memory as it was, and nothing it
/// does comes back except how it ended. Call it from a thread that holds no lock `work` needs; the
/// child has only that thread, so `work` must not wait for other threads (no TBB parallel code).
[[nodiscard]] ChildOutcome run_in_child(const std::function<void()>& work, const ChildLimits& limits);

/// "SIGSEGV", "SIGABRT", ... or "signal N".
[[nodiscard]] std::string signal_name(int signal);

} // namespace vox
