#include "core/staging_dir.hpp"

#include "core/error.hpp"

#include <unistd.h>

#include <system_error>

namespace vox {

StagingDir::StagingDir(std::filesystem::path destination) : m_destination(destination.lexically_normal())
{
    std::string name = m_destination.filename().string();
    if (name.empty() || name == "." || name == "..") name = "run";
    m_staging = m_destination.parent_path() / ("." + name + ".partial-" + std::to_string(::getpid()));
    std::error_code ec;
    std::filesystem::remove_all(m_staging, ec);
    std::filesystem::create_directories(m_staging, ec);
    if (ec) throw file_error(m_destination.string(), "cannot be written (" + ec.message() + ")");
}

StagingDir::~StagingDir()
{
    if (m_committed) return;
    std::error_code ec;
    std::filesystem::remove_all(m_staging, ec); // nothing to do about a failure here: the run has failed already
}

void StagingDir::commit()
{
    std::error_code ec;
    std::filesystem::create_directories(m_destination, ec);
    if (ec) throw file_error(m_destination.string(), "cannot be written (" + ec.message() + ")");
    for (const auto& entry : std::filesystem::directory_iterator(m_staging)) {
        std::filesystem::rename(entry.path(), m_destination / entry.path().filename(), ec);
        if (ec) throw file_error((m_destination / entry.path().filename()).string(), "cannot be written (" + ec.message() + ")");
    }
    std::filesystem::remove(m_staging, ec);
    m_committed = true;
}

} // namespace vox
