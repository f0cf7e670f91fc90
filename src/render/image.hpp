#pragma once
// A rendered picture: 8-bit RGBA, rows from the top, and its PNG file.

#include <cstdint>
#include <filesystem>
#include <vector>

namespace vox::render {

struct Image {
    int width = 0, height = 0;
    std::vector<std::uint8_t> rgba; ///< width * height * 4, row 0 at the top

    [[nodiscard]] const std::uint8_t* pixel(int x, int y) const { return rgba.data() + 4 * (static_cast<std::size_t>(y) * static_cast<std::size_t>(width) + static_cast<std::size_t>(x)); }
};

/// Writes `image` as a PNG, atomically (a failed write leaves nothing behind). Throws InputError
/// naming the file when it cannot be written.
void write_png(const std::filesystem::path& path, const Image& image);

} // namespace vox::render
