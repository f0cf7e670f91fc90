#pragma once
// The project's one logger (spdlog), writing to stderr. Quiet in tests and with --quiet.

#include <spdlog/spdlog.h>

namespace vox::log {

enum class Verbosity { quiet, normal, verbose };

/// Sets the level of the shared logger: quiet shows only errors, verbose adds debug messages.
void set_verbosity(Verbosity v);
[[nodiscard]] Verbosity verbosity();

/// The shared logger, created on first use.
[[nodiscard]] spdlog::logger& get();

template <class... Args> void info(spdlog::format_string_t<Args...> fmt, Args&&... args)
{
    get().info(fmt, std::forward<Args>(args)...);
}
template <class... Args> void warn(spdlog::format_string_t<Args...> fmt, Args&&... args)
{
    get().warn(fmt, std::forward<Args>(args)...);
}
template <class... Args> void debug(spdlog::format_string_t<Args...> fmt, Args&&... args)
{
    get().debug(fmt, std::forward<Args>(args)...);
}

} // namespace vox::log
