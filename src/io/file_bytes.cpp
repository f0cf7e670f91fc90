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

/// zlib's description of the last gzip error, without the "PATH: " zlib puts in front (our
/// messages start with the path already).
std::string gz_message(gzFile gz, const std::string& path, int& err)
{
    const char* msg = gzerror(gz, &err);
    std::string text = msg ? msg : "";
    if (text.starts_with(path + ": ")) text.erase(0, path.size() + 2);
    return text;
}

} // namespace

void check_input_file(const std::string& path)
{
    std::error_code ec;
    const auto st = std::filesystem::status(path, ec);
    if (!std::filesystem::exists(st)) {
        if (ec && ec != std::errc::no_such_file_or_directory && ec != std::errc::not_a_directory)
            throw file_error(path, "cannot open: " + ec.message());
        throw file_error(path, "no such file");
    }
    if (std::filesystem::is_directory(st)) throw file_error(path, "is a folder, not a file");
    if (!std::filesystem::is_regular_file(st)) throw file_error(path, "is not a regular file");
    errno = 0;
    if (!std::ifstream(path, std::ios::binary))
        throw file_error(path, std::string("cannot open: ") + (errno ? std::strerror(errno) : "permission denied"));
    const auto size = std::filesystem::file_size(path, ec);
    if (ec) throw file_error(path, "cannot read its size: " + ec.message());
    if (size == 0) throw file_error(path, "is empty");
}

bool is_gzip_file(const std::string& path)
{
    std::ifstream in(path, std::ios::binary);
    unsigned char magic[2] = {0, 0};
    in.read(reinterpret_cast<char*>(magic), 2);
    return in.gcount() == 2 && magic[0] == 0x1f && magic[1] == 0x8b;
}

std::vector<std::byte> read_file_bytes(const std::string& path)
{
    check_input_file(path);
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
            const std::string msg = gz_message(gz, path, err);
            gzclose(gz);
            throw file_error(path, "corrupt gzip data (" + msg + ")");
        }
        if (n == 0) break;
        used += static_cast<std::size_t>(n);
    }
    // gzread returns 0 at a truncated stream too; tell that apart from a clean end.
    int err = 0;
    const std::string what = gz_message(gz, path, err);
    const bool truncated = err != Z_OK && err != Z_STREAM_END;
    gzclose(gz);
    if (truncated) throw file_error(path, "corrupt or truncated gzip data (" + what + ")");
    if (used == 0) throw file_error(path, "is empty once decompressed (gzip of no data)");
    bytes.resize(used);
    return bytes;
}

FileHead read_file_head(const std::string& path, std::size_t max_bytes)
{
    check_input_file(path);
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
    // All the voxels but no end of stream: the checksum and size trailer was cut off, so nothing
    // vouches for the data.
    if (rc != Z_STREAM_END)
        throw file_error(what, "compressed data is truncated: it ends before its checksum (the gzip or zlib trailer)");
    out.resize(expected);
    return out;
}

} // namespace vox::io
