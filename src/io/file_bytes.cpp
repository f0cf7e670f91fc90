#include "io/file_bytes.hpp"

#include "core/error.hpp"
#include "core/memory_limit.hpp"

#include <zlib.h>

#include <cerrno>
#include <cstring>
#include <filesystem>
#include <fstream>

namespace vox::io {
namespace {
void check_readable(const std::string& path)
{
    std::error_code ec;
    const auto st = std::filesystem::status(path, ec);
    if (ec || !std::filesystem::exists(st)) throw file_error(path, "no such file");
    if (std::filesystem::is_directory(st)) throw file_error(path, "is a folder, not a file");
}
} // namespace

bool is_gzip_file(const std::string& path)
{
    std::ifstream in(path, std::ios::binary);
    unsigned char magic[2] = {0, 0};
    in.read(reinterpret_cast<char*>(magic), 2);
    return in.gcount() == 2 && magic[0] == 0x1f && magic[1] == 0x8b;
}

std::vector<std::byte> read_file_bytes(const std::string& path)
{
    check_readable(path);
    if (!is_gzip_file(path)) {
        std::ifstream in(path, std::ios::binary | std::ios::ate);
        if (!in) throw file_error(path, std::string("cannot open: ") + std::strerror(errno));
        const auto size = static_cast<std::uint64_t>(in.tellg());
        check_allocation(path, size, 1);
        std::vector<std::byte> bytes(size);
        in.seekg(0);
        in.read(reinterpret_cast<char*>(bytes.data()), static_cast<std::streamsize>(size));
        if (static_cast<std::uint64_t>(in.gcount()) != size) throw file_error(path, "read error");
        return bytes;
    }
    gzFile gz = gzopen(path.c_str(), "rb");
    if (!gz) throw file_error(path, std::string("cannot open: ") + std::strerror(errno));
    std::vector<std::byte> bytes;
    std::size_t used = 0;
    for (;;) {
        if (bytes.size() - used < (1u << 20)) {
            check_allocation(path + " (decompressed)", bytes.size() + (4u << 20), 1);
            bytes.resize(bytes.size() + (4u << 20));
        }
        const int n = gzread(gz, bytes.data() + used, static_cast<unsigned>(bytes.size() - used));
        if (n < 0) {
            int err = 0;
            std::string msg = gzerror(gz, &err);
            gzclose(gz);
            throw file_error(path, "corrupt gzip data (" + msg + ")");
        }
        if (n == 0) break;
        used += static_cast<std::size_t>(n);
    }
    // gzread returns 0 at a truncated stream too; tell that apart from a clean end.
    int err = 0;
    const char* msg = gzerror(gz, &err);
    const bool truncated = err != Z_OK && err != Z_STREAM_END;
    const std::string what = msg ? msg : "";
    gzclose(gz);
    if (truncated) throw file_error(path, "corrupt or truncated gzip data (" + what + ")");
    bytes.resize(used);
    return bytes;
}

FileHead read_file_head(const std::string& path, std::size_t max_bytes)
{
    std::error_code ec;
    if (!std::filesystem::is_regular_file(path, ec)) throw file_error(path, "no such file");
    std::ifstream in(path, std::ios::binary);
    if (!in) throw file_error(path, "cannot open");
    FileHead head;
    head.text.resize(max_bytes);
    in.read(head.text.data(), static_cast<std::streamsize>(head.text.size()));
    head.whole_file = static_cast<std::size_t>(in.gcount()) < head.text.size();
    head.text.resize(static_cast<std::size_t>(in.gcount()));
    return head;
}

void read_file_range(const std::string& file, std::uint64_t offset, std::byte* out, std::uint64_t count,
                     const std::string& what)
{
    std::ifstream in(file, std::ios::binary);
    in.seekg(static_cast<std::streamoff>(offset));
    in.read(reinterpret_cast<char*>(out), static_cast<std::streamsize>(count));
    if (!in || static_cast<std::uint64_t>(in.gcount()) != count)
        throw file_error(what, "cannot read " + std::to_string(count) + " bytes at offset " + std::to_string(offset) +
                                   " of '" + file + "'");
}

std::vector<std::byte> inflate_exact(const std::byte* data, std::size_t size, std::size_t expected,
                                     const std::string& what)
{
    check_allocation(what, expected, 1);
    std::vector<std::byte> out(expected + 1); // one spare byte detects data that is too long
    z_stream zs{};
    if (inflateInit2(&zs, 15 + 32) != Z_OK) throw file_error(what, "cannot start zlib");
    zs.next_in = reinterpret_cast<Bytef*>(const_cast<std::byte*>(data));
    zs.avail_in = static_cast<uInt>(size);
    zs.next_out = reinterpret_cast<Bytef*>(out.data());
    zs.avail_out = static_cast<uInt>(out.size());
    const int rc = inflate(&zs, Z_FINISH);
    const std::size_t produced = zs.total_out;
    inflateEnd(&zs);
    if (rc != Z_STREAM_END && rc != Z_BUF_ERROR && rc != Z_OK)
        throw file_error(what, "corrupt compressed data (zlib error " + std::to_string(rc) + ")");
    if (produced != expected)
        throw file_error(what, "compressed data holds " + std::to_string(produced) + (produced > expected ? "+" : "") +
                                   " bytes, expected " + std::to_string(expected));
    out.resize(expected);
    return out;
}

} // namespace vox::io
