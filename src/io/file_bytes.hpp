#pragma once
// Reading whole files, plain or gzip-compressed, with the size checked before allocating.

#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

namespace vox::io {

/// Checks that `path` names a non-empty regular file that can be opened, before a reader (ours or a
/// library's) looks inside. Throws InputError "PATH: no such file", "PATH: is a folder, not a
/// file", "PATH: is not a regular file", "PATH: cannot open: REASON" or "PATH: is empty".
void check_input_file(const std::string& path);

/// True when the file starts with the gzip magic bytes (1f 8b).
[[nodiscard]] bool is_gzip_file(const std::string& path);

/// Reads the whole file, decompressing it when it is gzip. Throws InputError naming the file when
/// it fails check_input_file, is corrupt or truncated gzip, is empty once decompressed, or is
/// larger than the memory limit once decompressed.
[[nodiscard]] std::vector<std::byte> read_file_bytes(const std::string& path);

/// The first bytes of a file, as read by read_file_head.
struct FileHead {
    std::string text;        ///< at most the `max_bytes` asked for
    bool whole_file = false; ///< the file is no longer than `text`
};

/// Reads at most the first `max_bytes` of a plain (uncompressed) file, for formats with a text
/// header before binary data. Throws InputError as check_input_file does.
[[nodiscard]] FileHead read_file_head(const std::string& path, std::size_t max_bytes);

/// Reads `count` bytes at byte `offset` of `file` into `out`. Throws InputError "WHAT: cannot read
/// COUNT bytes at offset OFFSET of 'FILE'" when the file holds fewer; `what` names the data in
/// messages.
void read_file_range(const std::string& file, std::uint64_t offset, std::byte* out, std::uint64_t count,
                     const std::string& what);

/// Inflates zlib or gzip data (auto-detected) that must decompress to exactly `expected` bytes.
/// `what` names the data in messages. Throws InputError when corrupt, short or long.
[[nodiscard]] std::vector<std::byte> inflate_exact(const std::byte* data, std::size_t size, std::size_t expected,
                                                   const std::string& what);
} // namespace vox::io
