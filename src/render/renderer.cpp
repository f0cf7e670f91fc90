#include "render/renderer.hpp"

#include "render/gl_program.hpp"

#include "core/error.hpp"

#define GL_GLEXT_PROTOTYPES
#include <GL/gl.h>
#include <GL/glext.h>

#include <algorithm>
#include <stdexcept>
#include <string>

namespace vox::render {
namespace {

const char* const mesh_vertex = R"(#version 330 core
layout(location = 0) in vec3 position;
layout(location = 1) in vec3 normal;
layout(location = 2) in vec3 color;
uniform mat4 view, projection;
out vec3 v_normal, v_color, v_eye_position;
void main() {
    vec4 p = view * vec4(position, 1.0);
    v_eye_position = p.xyz;
    v_normal = mat3(view) * normal;
    v_color = color;
    gl_Position = projection * p;
})";

const char* const mesh_fragment = R"(#version 330 core
in vec3 v_normal, v_color, v_eye_position;
uniform float alpha;
uniform bool orthographic;
out vec4 frag;
void main() {
    vec3 n = normalize(v_normal);
    vec3 to_eye = orthographic ? vec3(0, 0, 1) : normalize(-v_eye_position);
    if (dot(n, to_eye) < 0.0) n = -n; // lit from both sides
    vec3 key = normalize(vec3(-0.45, 0.6, 0.65)), fill = normalize(vec3(0.6, -0.2, 0.4));
    float diffuse = 0.62 * max(dot(n, key), 0.0) + 0.3 * max(dot(n, fill), 0.0) + 0.3;
    float specular = 0.12 * pow(max(dot(n, normalize(key + to_eye)), 0.0), 40.0);
    vec3 c = v_color * diffuse + vec3(specular);
    frag = vec4(min(c, vec3(1.0)), alpha); // colours are display colours
})";

const char* const line_vertex = R"(#version 330 core
layout(location = 0) in vec3 position;
layout(location = 2) in vec3 color;
uniform mat4 view, projection;
out vec3 v_color;
void main() {
    v_color = color;
    gl_Position = projection * view * vec4(position, 1.0);
})";

const char* const line_fragment = R"(#version 330 core
in vec3 v_color;
uniform float alpha;
out vec4 frag;
void main() { frag = vec4(v_color, alpha); })";

/// One mesh's buffers, alive for one draw.
struct Uploaded {
    GLuint vao = 0, buffers[4] = {0, 0, 0, 0};
    explicit Uploaded(const DrawMesh& m)
    {
        glGenVertexArrays(1, &vao);
        glBindVertexArray(vao);
        glGenBuffers(4, buffers);
        auto attribute = [&](int slot, const std::vector<Eigen::Vector3f>& data) {
            glBindBuffer(GL_ARRAY_BUFFER, buffers[slot]);
            glBufferData(GL_ARRAY_BUFFER, static_cast<GLsizeiptr>(data.size() * sizeof(Eigen::Vector3f)), data.data(), GL_STATIC_DRAW);
            glVertexAttribPointer(static_cast<GLuint>(slot), 3, GL_FLOAT, GL_FALSE, sizeof(Eigen::Vector3f), nullptr);
            glEnableVertexAttribArray(static_cast<GLuint>(slot));
        };
        attribute(0, m.positions);
        if (!m.lines) attribute(1, m.normals);
        attribute(2, m.colors);
        glBindBuffer(GL_ELEMENT_ARRAY_BUFFER, buffers[3]);
        glBufferData(GL_ELEMENT_ARRAY_BUFFER, static_cast<GLsizeiptr>(m.indices.size() * sizeof(std::uint32_t)), m.indices.data(), GL_STATIC_DRAW);
    }
    ~Uploaded()
    {
        glDeleteBuffers(4, buffers);
        glDeleteVertexArrays(1, &vao);
    }
    Uploaded(const Uploaded&) = delete;
    Uploaded& operator=(const Uploaded&) = delete;
};

} // namespace

Renderer::Renderer()
{
    m_program = link_program(mesh_vertex, mesh_fragment);
    m_line_program = link_program(line_vertex, line_fragment);
}

Renderer::~Renderer()
{
    glDeleteProgram(m_program);
    glDeleteProgram(m_line_program);
    const GLuint fbos[] = {m_msaa_fbo, m_fbo}, renderbuffers[] = {m_msaa_color, m_msaa_depth, m_color};
    glDeleteFramebuffers(2, fbos);
    glDeleteRenderbuffers(3, renderbuffers);
}

void Renderer::resize(int width, int height)
{
    if (width == m_width && height == m_height) return;
    if (!m_msaa_fbo) {
        glGenFramebuffers(1, &m_msaa_fbo);
        glGenFramebuffers(1, &m_fbo);
        glGenRenderbuffers(1, &m_msaa_color);
        glGenRenderbuffers(1, &m_msaa_depth);
        glGenRenderbuffers(1, &m_color);
    }
    glBindRenderbuffer(GL_RENDERBUFFER, m_msaa_color);
    glRenderbufferStorageMultisample(GL_RENDERBUFFER, 4, GL_RGBA8, width, height);
    glBindRenderbuffer(GL_RENDERBUFFER, m_msaa_depth);
    glRenderbufferStorageMultisample(GL_RENDERBUFFER, 4, GL_DEPTH_COMPONENT24, width, height);
    glBindFramebuffer(GL_FRAMEBUFFER, m_msaa_fbo);
    glFramebufferRenderbuffer(GL_FRAMEBUFFER, GL_COLOR_ATTACHMENT0, GL_RENDERBUFFER, m_msaa_color);
    glFramebufferRenderbuffer(GL_FRAMEBUFFER, GL_DEPTH_ATTACHMENT, GL_RENDERBUFFER, m_msaa_depth);
    if (glCheckFramebufferStatus(GL_FRAMEBUFFER) != GL_FRAMEBUFFER_COMPLETE) throw std::runtime_error("render: multisampled framebuffer incomplete");
    glBindRenderbuffer(GL_RENDERBUFFER, m_color);
    glRenderbufferStorage(GL_RENDERBUFFER, GL_RGBA8, width, height);
    glBindFramebuffer(GL_FRAMEBUFFER, m_fbo);
    glFramebufferRenderbuffer(GL_FRAMEBUFFER, GL_COLOR_ATTACHMENT0, GL_RENDERBUFFER, m_color);
    if (glCheckFramebufferStatus(GL_FRAMEBUFFER) != GL_FRAMEBUFFER_COMPLETE) throw std::runtime_error("render: framebuffer incomplete");
    m_width = width;
    m_height = height;
}

void Renderer::draw(const std::vector<DrawMesh>& meshes, const Camera& camera, int width, int height)
{
    glViewport(0, 0, width, height);
    glClearColor(background[0] / 255.0f, background[1] / 255.0f, background[2] / 255.0f, 1.0f);
    glClear(GL_COLOR_BUFFER_BIT | GL_DEPTH_BUFFER_BIT);
    glEnable(GL_DEPTH_TEST);
    glEnable(GL_MULTISAMPLE);
    const Eigen::Matrix4f view = camera.view(), projection = camera.projection(static_cast<double>(width) / height);
    auto draw_one = [&](const DrawMesh& m) {
        if (m.indices.empty()) return;
        const GLuint program = m.lines ? m_line_program : m_program;
        glUseProgram(program);
        glUniformMatrix4fv(glGetUniformLocation(program, "view"), 1, GL_FALSE, view.data());
        glUniformMatrix4fv(glGetUniformLocation(program, "projection"), 1, GL_FALSE, projection.data());
        glUniform1f(glGetUniformLocation(program, "alpha"), m.alpha);
        if (!m.lines) glUniform1i(glGetUniformLocation(program, "orthographic"), camera.orthographic);
        const Uploaded u(m);
        glDrawElements(m.lines ? GL_LINES : GL_TRIANGLES, static_cast<GLsizei>(m.indices.size()), GL_UNSIGNED_INT, nullptr);
    };
    for (const DrawMesh& m : meshes)
        if (m.alpha >= 1.0f) draw_one(m);
    glEnable(GL_BLEND);
    glBlendFunc(GL_SRC_ALPHA, GL_ONE_MINUS_SRC_ALPHA);
    glDepthMask(GL_FALSE);
    for (const DrawMesh& m : meshes)
        if (m.alpha < 1.0f) draw_one(m);
    glDepthMask(GL_TRUE);
    glDisable(GL_BLEND);
}

Image read_pixels(int width, int height)
{
    Image image;
    image.width = width;
    image.height = height;
    image.rgba.resize(static_cast<std::size_t>(width) * static_cast<std::size_t>(height) * 4);
    glPixelStorei(GL_PACK_ALIGNMENT, 1);
    glReadPixels(0, 0, width, height, GL_RGBA, GL_UNSIGNED_BYTE, image.rgba.data());
    const std::size_t row = static_cast<std::size_t>(width) * 4;
    for (int y = 0; y < height / 2; ++y) // OpenGL's rows run from the bottom
        std::swap_ranges(image.rgba.begin() + static_cast<std::ptrdiff_t>(row * static_cast<std::size_t>(y)),
                         image.rgba.begin() + static_cast<std::ptrdiff_t>(row * static_cast<std::size_t>(y + 1)),
                         image.rgba.begin() + static_cast<std::ptrdiff_t>(row * static_cast<std::size_t>(height - 1 - y)));
    for (std::size_t i = 3; i < image.rgba.size(); i += 4) image.rgba[i] = 255;
    return image;
}

Image Renderer::render(const std::vector<DrawMesh>& meshes, const Camera& camera, int width, int height)
{
    if (width < 1 || height < 1 || width > 8192 || height > 8192)
        throw InputError("picture size " + std::to_string(width) + " x " + std::to_string(height) + ": each side must be 1 to 8192 pixels");
    resize(width, height);
    glBindFramebuffer(GL_FRAMEBUFFER, m_msaa_fbo);
    draw(meshes, camera, width, height);
    // Resolve the samples, then read back.
    glBindFramebuffer(GL_READ_FRAMEBUFFER, m_msaa_fbo);
    glBindFramebuffer(GL_DRAW_FRAMEBUFFER, m_fbo);
    glBlitFramebuffer(0, 0, width, height, 0, 0, width, height, GL_COLOR_BUFFER_BIT, GL_NEAREST);
    glBindFramebuffer(GL_READ_FRAMEBUFFER, m_fbo);
    Image image = read_pixels(width, height);
    glBindFramebuffer(GL_FRAMEBUFFER, 0);
    if (glGetError() != GL_NO_ERROR) throw std::runtime_error("render: OpenGL reported an error while drawing");
    return image;
}

} // namespace vox::render
