#include "core/log.hpp"

#include <spdlog/sinks/stdout_color_sinks.h>

#include <atomic>

namespace vox::log {
namespace {
std::atomic<Verbosity> g_verbosity{Verbosity::normal};

spdlog::level::level_enum to_level(Verbosity v)
{
    switch (v) {
    case Verbosity::quiet: return spdlog::level::err;
    case Verbosity::verbose: return spdlog::level::debug;
    case Verbosity::normal: break;
    }
    return spdlog::level::info;
}
} // namespace

spdlog::logger& get()
{
    static std::shared_ptr<spdlog::logger> logger = [] {
        auto l = spdlog::stderr_color_mt("voxsculpt");
        l->set_pattern("%^%l%$: %v");
        l->set_level(to_level(g_verbosity.load()));
        return l;
    }();
    return *logger;
}

void set_verbosity(Verbosity v)
{
    g_verbosity = v;
    get().set_level(to_level(v));
}

Verbosity verbosity() { return g_verbosity.load(); }

} // namespace vox::log
