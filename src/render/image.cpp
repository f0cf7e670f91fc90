#include "render/image.hpp"

#include "core/atomic_file.hpp"
#include "core/error.hpp"

#include <stb/stb_image_write.h>

namespace vox::render {

void write_png(const std::filesystem::path& path, const Image& image)
{
    write_atomically(path, [&](const std::filesystem::path& tmp) {
        if (!stbi_write_png(tmp.c_str(), image.width, image.height, 4, image.rgba.data(), 4 * image.width))
            throw InputError(path.string() + ": cannot write the PNG file");
    });
}

} // namespace vox::render
