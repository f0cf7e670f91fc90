#pragma once
// Draws meshes into an offscreen framebuffer (4x multisampled) and reads the picture back. Needs
// a current OpenGL 3.3 core context (OffscreenContext, or a window's). Lighting: a key light
// over the viewer's left shoulder, a fill light and ambient, lit from both sides (a cut opens
// the surface to view from inside too), Blinn-Phong highlights; a plain background so pictures
// can be measured.

#include "render/camera.hpp"
#include "render/draw_mesh.hpp"
#include "render/image.hpp"

#include <vector>

namespace vox::render {

class Renderer {
public:
    /// Background colour of every picture, RGB 0-255.
    static constexpr std::uint8_t background[3] = {236, 238, 242};

    Renderer();
    ~Renderer();
    Renderer(const Renderer&) = delete;
    Renderer& operator=(const Renderer&) = delete;

    /// The picture of `meshes` seen by `camera`, `width` x `height` pixels (1 to 8192 each; throws
    /// InputError otherwise), drawn offscreen. Opaque meshes first, then the translucent ones.
    [[nodiscard]] Image render(const std::vector<DrawMesh>& meshes, const Camera& camera, int width, int height);
    /// Draws them into the framebuffer now bound (a window's), clearing it first.
    void draw(const std::vector<DrawMesh>& meshes, const Camera& camera, int width, int height);

private:
    void resize(int width, int height);

    unsigned m_program = 0, m_line_program = 0;
    unsigned m_msaa_fbo = 0, m_msaa_color = 0, m_msaa_depth = 0, m_fbo = 0, m_color = 0;
    int m_width = 0, m_height = 0;
};

/// The bound read framebuffer's pixels, rows from the top.
[[nodiscard]] Image read_pixels(int width, int height);

} // namespace vox::render
