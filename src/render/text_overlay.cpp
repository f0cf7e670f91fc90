#include "render/text_overlay.hpp"

#include "render/gl_program.hpp"

#define GL_GLEXT_PROTOTYPES
#include <GL/gl.h>
#include <GL/glext.h>
#include <stb/stb_easy_font.h>

#include <algorithm>
#include <stdexcept>
#include <vector>

namespace vox::render {
namespace {

const char* const vertex_source = R"(#version 330 core
layout(location = 0) in vec2 pixel;
uniform vec2 size;
void main() { gl_Position = vec4(2.0 * pixel.x / size.x - 1.0, 1.0 - 2.0 * pixel.y / size.y, 0.0, 1.0); })";

const char* const fragment_source = R"(#version 330 core
uniform vec4 color;
out vec4 frag;
void main() { frag = color; })";

} // namespace

TextOverlay::TextOverlay()
{
    m_program = link_program(vertex_source, fragment_source);
    glGenVertexArrays(1, &m_vao);
    glGenBuffers(1, &m_buffer);
}

TextOverlay::~TextOverlay()
{
    glDeleteBuffers(1, &m_buffer);
    glDeleteVertexArrays(1, &m_vao);
    glDeleteProgram(m_program);
}

void TextOverlay::draw(const std::string& text, int x, int y, int width, int height, float scale)
{
    if (text.empty()) return;
    // stb_easy_font writes quads of 4 vertices (x, y, z, colour: 16 bytes each); up to ~270
    // bytes a character.
    std::vector<char> quads(text.size() * 300 + 1000);
    std::string copy = text;
    const int count = stb_easy_font_print(0.0f, 0.0f, copy.data(), nullptr, quads.data(), static_cast<int>(quads.size()));
    const float w = static_cast<float>(stb_easy_font_width(copy.data())) * scale, h = static_cast<float>(stb_easy_font_height(copy.data())) * scale;
    std::vector<float> triangles; // pixel coordinates, two triangles a quad
    const float pad = 6.0f;
    auto quad = [&](float x0, float y0, float x1, float y1) {
        for (const float v : {x0, y0, x1, y0, x1, y1, x0, y0, x1, y1, x0, y1}) triangles.push_back(v);
    };
    quad(static_cast<float>(x) - pad, static_cast<float>(y) - pad, static_cast<float>(x) + w + pad, static_cast<float>(y) + h + pad); // the panel
    for (int q = 0; q < count; ++q) {
        const auto* v = reinterpret_cast<const float*>(quads.data() + 64 * q); // 4 vertices of (x, y, z, rgba)
        quad(static_cast<float>(x) + scale * v[0], static_cast<float>(y) + scale * v[1], static_cast<float>(x) + scale * v[8],
             static_cast<float>(y) + scale * v[9]);
    }
    const GLboolean depth = glIsEnabled(GL_DEPTH_TEST);
    glDisable(GL_DEPTH_TEST);
    glEnable(GL_BLEND);
    glBlendFunc(GL_SRC_ALPHA, GL_ONE_MINUS_SRC_ALPHA);
    glUseProgram(m_program);
    glUniform2f(glGetUniformLocation(m_program, "size"), static_cast<float>(width), static_cast<float>(height));
    glBindVertexArray(m_vao);
    glBindBuffer(GL_ARRAY_BUFFER, m_buffer);
    glBufferData(GL_ARRAY_BUFFER, static_cast<GLsizeiptr>(triangles.size() * sizeof(float)), triangles.data(), GL_STREAM_DRAW);
    glVertexAttribPointer(0, 2, GL_FLOAT, GL_FALSE, 2 * sizeof(float), nullptr);
    glEnableVertexAttribArray(0);
    glUniform4f(glGetUniformLocation(m_program, "color"), 1.0f, 1.0f, 1.0f, 0.75f);
    glDrawArrays(GL_TRIANGLES, 0, 6);
    glUniform4f(glGetUniformLocation(m_program, "color"), 0.1f, 0.1f, 0.12f, 1.0f);
    glDrawArrays(GL_TRIANGLES, 6, static_cast<GLsizei>(triangles.size() / 2 - 6));
    glDisable(GL_BLEND);
    if (depth) glEnable(GL_DEPTH_TEST);
}

} // namespace vox::render
