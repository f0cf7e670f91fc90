#pragma once
// Reading whole files, plain or gzip-compressed, with the size checked before allocating.

#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

namespace vox::io {

/// True when the file starts with the gzip magic bytes (1f 8b).
[[nodiscard]] bool is_gzip_file(const std::string& path);

/// Reads the whole file, decompressing it when it is gzip. Throws InputError naming the file when
/// it is missing, unreadable, corrupt, or larger than the memory limit once decompressed.
[[nodiscard]] std::vector<std::byte> read_file_bytes(const std::string& path);

/// Inflates zlib or gzip data (auto-detected) that must decompress to exactly `expected` bytes.
/// `what` names the data in messages. Throws InputError when corrupt, short or long.
[[nodiscard]] std::vector<std::byte> inflate_exact(const std::byte* data, std::size_t size, std::size_t expected,
                                                   const std::string& what);
} // namespace vox::io
