#include "core/progress.hpp"

#include "core/log.hpp"

#include <unistd.h>

#include <cstdio>

namespace vox {

Progress::Progress(std::string label, std::uint64_t total)
    : m_label(std::move(label)), m_total(total == 0 ? 1 : total),
      m_enabled(isatty(STDERR_FILENO) != 0 && log::verbosity() != log::Verbosity::quiet),
      m_start(std::chrono::steady_clock::now()), m_last_draw(m_start)
{
}

Progress::~Progress() { finish(); }

void Progress::update(std::uint64_t done)
{
    if (!m_enabled) return;
    const auto now = std::chrono::steady_clock::now();
    if (now - m_start < std::chrono::seconds(1)) return;
    if (m_drawn && now - m_last_draw < std::chrono::milliseconds(100)) return;
    m_last_draw = now;
    m_drawn = true;
    const double f = std::min(1.0, static_cast<double>(done) / static_cast<double>(m_total));
    constexpr int width = 30;
    const int filled = static_cast<int>(f * width);
    std::fprintf(stderr, "\r%s [%.*s%*s] %3d%%", m_label.c_str(), filled,
                 "##############################", width - filled, "", static_cast<int>(f * 100));
    std::fflush(stderr);
}

void Progress::finish()
{
    if (!m_drawn) return;
    std::fprintf(stderr, "\r\033[K");
    std::fflush(stderr);
    m_drawn = false;
}

} // namespace vox
