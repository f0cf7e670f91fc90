#include "core/atomic_file.hpp"

#include "core/error.hpp"

#include <unistd.h>

#include <string>
#include <system_error>

namespace vox {

void write_atomically(const std::filesystem::path& target,
                      const std::function<void(const std::filesystem::path&)>& write)
{
    namespace fs = std::filesystem;
    const fs::path parent = target.has_parent_path() ? target.parent_path() : fs::path(".");
    std::error_code ec;
    fs::create_directories(parent, ec);
    if (ec) throw file_error(target.string(), "cannot create folder " + parent.string() + ": " + ec.message());

    // Keep the extension last: some writers pick their format from it.
    const fs::path tmp = parent / (".tmp-" + std::to_string(::getpid()) + "-" + target.filename().string());
    try {
        write(tmp);
    } catch (...) {
        fs::remove(tmp, ec);
        throw;
    }
    fs::rename(tmp, target, ec);
    if (ec) {
        fs::remove(tmp, ec);
        throw file_error(target.string(), "cannot move the written file into place");
    }
}

} // namespace vox
