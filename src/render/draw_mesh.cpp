#include "render/draw_mesh.hpp"

#include <Eigen/Geometry>

#include <array>

namespace vox::render {

void compute_normals(DrawMesh& mesh)
{
    mesh.normals.assign(mesh.positions.size(), Eigen::Vector3f::Zero());
    for (std::size_t t = 0; t + 2 < mesh.indices.size(); t += 3) {
        const std::uint32_t a = mesh.indices[t], b = mesh.indices[t + 1], c = mesh.indices[t + 2];
        const Eigen::Vector3f n = (mesh.positions[b] - mesh.positions[a]).cross(mesh.positions[c] - mesh.positions[a]);
        mesh.normals[a] += n;
        mesh.normals[b] += n;
        mesh.normals[c] += n;
    }
    for (Eigen::Vector3f& n : mesh.normals) {
        const float length = n.norm();
        n = length > 0.0f ? Eigen::Vector3f(n / length) : Eigen::Vector3f::UnitZ();
    }
}

Eigen::Vector3f label_color(std::int32_t label)
{
    // Ordered so that the hash below gives the bundled liver (255) its red-brown and the lesion
    // label beside it (127) a pale yellow.
    static const std::array<Eigen::Vector3f, 8> palette{
        Eigen::Vector3f(0.45f, 0.65f, 0.40f), // green
        Eigen::Vector3f(0.65f, 0.50f, 0.75f), // violet
        Eigen::Vector3f(0.90f, 0.60f, 0.30f), // orange
        Eigen::Vector3f(0.88f, 0.80f, 0.52f), // pale yellow (lesion, fat)
        Eigen::Vector3f(0.62f, 0.22f, 0.18f), // red-brown (liver)
        Eigen::Vector3f(0.30f, 0.45f, 0.75f), // blue (vessels)
        Eigen::Vector3f(0.75f, 0.35f, 0.40f), // pink (muscle)
        Eigen::Vector3f(0.50f, 0.70f, 0.75f), // teal
    };
    if (label == 0) return {0.76f, 0.60f, 0.48f}; // clay
    // Multiplicative hashing spreads neighbouring labels (1, 2, 3 or 127, 255) over the palette.
    const auto h = static_cast<std::uint32_t>(label) * 2654435761u;
    return palette[(h >> 29) % palette.size()];
}

} // namespace vox::render
