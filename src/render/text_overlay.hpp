#pragma once
// Lines of text over the picture (rates, the tool, the key map): stb_easy_font's quads on a
// translucent panel, drawn in pixels from the top-left corner. Needs a current OpenGL 3.3 context.

#include <string>

namespace vox::render {

class TextOverlay {
public:
    TextOverlay();
    ~TextOverlay();
    TextOverlay(const TextOverlay&) = delete;
    TextOverlay& operator=(const TextOverlay&) = delete;

    /// Draws `text` (lines separated by '\n') at (x, y) pixels from the top-left of a
    /// `width` x `height` framebuffer, `scale` times stb_easy_font's 7-pixel-high characters.
    void draw(const std::string& text, int x, int y, int width, int height, float scale = 2.0f);

private:
    unsigned m_program = 0, m_vao = 0, m_buffer = 0;
};

} // namespace vox::render
