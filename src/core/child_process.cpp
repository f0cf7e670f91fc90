#include "core/child_process.hpp"

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <csignal>
#include <cstdio>
#include <cstring>
#include <fcntl.h>
#include <new>
#include <poll.h>
#include <stdexcept>
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

// In a build with sanitizers (fuzzing), the hook their reports end with; null otherwise.
extern "C" void __sanitizer_set_death_callback(void (*callback)()) __attribute__((weak));

namespace vox {
namespace {

// The child's exit codes (it leaves with _exit, running no destructor of the parent's objects).
constexpr int k_exit_ok = 0;
constexpr int k_exit_threw = 3;
constexpr int k_exit_no_memory = 4;
constexpr int k_exit_sanitizer = 5; ///< a sanitizer stopped it (instrumented builds)
constexpr std::size_t k_max_message = 1000;

/// The process's current address-space size in bytes (first field of /proc/self/statm, in pages).
std::uint64_t address_space_bytes()
{
    std::FILE* f = std::fopen("/proc/self/statm", "r");
    if (!f) return 0;
    unsigned long long pages = 0;
    const int got = std::fscanf(f, "%llu", &pages);
    std::fclose(f);
    return got == 1 ? pages * static_cast<std::uint64_t>(sysconf(_SC_PAGESIZE)) : 0;
}

[[noreturn]] void child_main(const std::function<void()>& work, const ChildLimits& limits, int report_fd)
{
    // A crash here is the parent's to report: handlers inherited from it (a sanitizer's, a
    // fuzzer's that would save the input as a failure of its own) give way to the default.
    for (const int s : {SIGSEGV, SIGBUS, SIGABRT, SIGFPE, SIGILL}) std::signal(s, SIG_DFL);
    if (__sanitizer_set_death_callback) __sanitizer_set_death_callback([] { _exit(k_exit_sanitizer); });
    if (limits.silence_stderr) {
        const int null_fd = open("/dev/null", O_WRONLY);
        if (null_fd >= 0) dup2(null_fd, STDERR_FILENO);
    }
    const rlimit no_core{0, 0};
    setrlimit(RLIMIT_CORE, &no_core); // a crash on a hostile file is expected, not worth a core dump
    const std::uint64_t start = address_space_bytes();
    if (start > 0) {
        const rlimit memory{start + limits.memory_bytes, start + limits.memory_bytes};
        setrlimit(RLIMIT_AS, &memory);
    }
    int code = k_exit_ok;
    try {
        work();
    } catch (const std::bad_alloc&) {
        code = k_exit_no_memory;
    } catch (const std::exception& e) {
        const std::size_t n = std::min(std::strlen(e.what()), k_max_message);
        if (write(report_fd, e.what(), n) < 0) {
        } // nothing to do: the parent then reports the failure without its message
        code = k_exit_threw;
    } catch (...) {
        code = k_exit_threw;
    }
    _exit(code);
}

} // namespace

ChildOutcome run_in_child(const std::function<void()>& work, const ChildLimits& limits)
{
    int fds[2];
    if (pipe2(fds, O_CLOEXEC) != 0) throw std::runtime_error(std::string("pipe: ") + std::strerror(errno));
    std::fflush(nullptr); // buffered output would otherwise be written twice
    const pid_t pid = fork();
    if (pid < 0) {
        close(fds[0]);
        close(fds[1]);
        throw std::runtime_error(std::string("fork: ") + std::strerror(errno));
    }
    if (pid == 0) {
        close(fds[0]);
        child_main(work, limits, fds[1]);
    }
    close(fds[1]);

    // Read the child's message until it closes the pipe (it exits) or the time is up.
    using clock = std::chrono::steady_clock;
    const auto deadline = clock::now() + std::chrono::duration<double>(limits.seconds);
    std::string message;
    bool timed_out = false;
    for (;;) {
        const auto left = std::chrono::duration_cast<std::chrono::milliseconds>(deadline - clock::now()).count();
        if (left <= 0) {
            timed_out = true;
            break;
        }
        pollfd p{fds[0], POLLIN, 0};
        const int ready = poll(&p, 1, static_cast<int>(std::min<long long>(left, 1000)));
        if (ready < 0 && errno == EINTR) continue;
        if (ready <= 0) continue;
        char buffer[512];
        const ssize_t n = read(fds[0], buffer, sizeof buffer);
        if (n > 0 && message.size() < k_max_message) message.append(buffer, static_cast<std::size_t>(n));
        if (n == 0 || (n < 0 && errno != EINTR && errno != EAGAIN)) break; // closed: the child is ending
    }
    close(fds[0]);
    if (timed_out) kill(pid, SIGKILL);
    int status = 0;
    while (waitpid(pid, &status, 0) < 0 && errno == EINTR) {
    }

    ChildOutcome out;
    if (timed_out) {
        out.kind = ChildOutcome::Kind::timed_out;
    } else if (WIFSIGNALED(status)) {
        out.kind = ChildOutcome::Kind::crashed;
        out.signal = WTERMSIG(status);
    } else if (WEXITSTATUS(status) == k_exit_no_memory) {
        out.kind = ChildOutcome::Kind::out_of_memory;
    } else if (WEXITSTATUS(status) == k_exit_sanitizer) {
        out.kind = ChildOutcome::Kind::crashed; // what a sanitizer found is what would crash, or worse, without it
    } else if (WEXITSTATUS(status) != k_exit_ok) {
        out.kind = ChildOutcome::Kind::failed;
        out.message = message.substr(0, k_max_message);
    }
    return out;
}

std::string signal_name(int signal)
{
    switch (signal) {
    case SIGSEGV: return "SIGSEGV";
    case SIGBUS: return "SIGBUS";
    case SIGABRT: return "SIGABRT";
    case SIGFPE: return "SIGFPE";
    case SIGILL: return "SIGILL";
    case SIGKILL: return "SIGKILL";
    default: return "signal " + std::to_string(signal);
    }
}

} // namespace vox
