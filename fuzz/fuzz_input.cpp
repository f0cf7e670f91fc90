#include "fuzz_input.hpp"

#include "core/log.hpp"
#include "core/memory_limit.hpp"

#include <unistd.h>

#include <filesystem>
#include <fstream>

namespace vox::fuzz {

namespace {

/// This process's scratch folder, removed when it exits. In memory when the machine has /dev/shm:
/// libFuzzer runs thousands of inputs a second.
struct ScratchFolder {
    std::filesystem::path path;
    ScratchFolder()
    {
        const std::filesystem::path shm = "/dev/shm";
        const auto base = std::filesystem::is_directory(shm) ? shm : std::filesystem::temp_directory_path();
        path = base / ("voxsculpt-fuzz-" + std::to_string(::getpid()));
        std::filesystem::create_directories(path);
    }
    ~ScratchFolder()
    {
        std::error_code ec;
        std::filesystem::remove_all(path, ec);
    }
};

} // namespace

std::string input_file(const std::uint8_t* data, std::size_t size, const std::string& name)
{
    static const ScratchFolder folder;
    const std::filesystem::path path = folder.path / name;
    std::ofstream out(path, std::ios::binary | std::ios::trunc);
    out.write(reinterpret_cast<const char*>(data), static_cast<std::streamsize>(size));
    return path.string();
}

std::size_t& refused_count()
{
    static std::size_t count = 0;
    return count;
}

std::string& last_refusal()
{
    static std::string text;
    return text;
}

bool is_gzip(const std::uint8_t* data, std::size_t size) { return size >= 2 && data[0] == 0x1f && data[1] == 0x8b; }

void setup()
{
    static const bool once = [] {
        set_memory_limit_bytes(std::uint64_t{256} << 20);
        log::set_verbosity(log::Verbosity::quiet);
        return true;
    }();
    static_cast<void>(once);
}

} // namespace vox::fuzz
