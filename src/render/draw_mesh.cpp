#include "render/draw_mesh.hpp"

#include <Eigen/Geometry>


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

void smooth_for_display(DrawMesh& mesh, int iterations)
{
    if (iterations <= 0 || mesh.lines) return;
    // Neighbours of each vertex along the triangles' edges (each edge from both of its triangles:
    // the weights stay uniform on a closed mesh).
    const std::size_t n = mesh.positions.size();
    std::vector<std::uint32_t> start(n + 1, 0), neighbours;
    for (const std::uint32_t v : mesh.indices) start[v + 1] += 2;
    for (std::size_t v = 0; v < n; ++v) start[v + 1] += start[v];
    neighbours.resize(start[n]);
    std::vector<std::uint32_t> fill(start.begin(), start.end() - 1);
    for (std::size_t t = 0; t + 2 < mesh.indices.size(); t += 3)
        for (int c = 0; c < 3; ++c) {
            const std::uint32_t v = mesh.indices[t + static_cast<std::size_t>(c)];
            neighbours[fill[v]++] = mesh.indices[t + static_cast<std::size_t>((c + 1) % 3)];
            neighbours[fill[v]++] = mesh.indices[t + static_cast<std::size_t>((c + 2) % 3)];
        }
    std::vector<Eigen::Vector3f> next(mesh.positions);
    for (int it = 0; it < 2 * iterations; ++it) {
        const float factor = it % 2 == 0 ? 0.5f : -0.53f;
        for (std::size_t v = 0; v < n; ++v) {
            if (start[v] == start[v + 1]) continue;
            Eigen::Vector3f mean = Eigen::Vector3f::Zero();
            for (std::uint32_t k = start[v]; k < start[v + 1]; ++k) mean += mesh.positions[neighbours[k]];
            mean /= static_cast<float>(start[v + 1] - start[v]);
            next[v] = mesh.positions[v] + factor * (mean - mesh.positions[v]);
        }
        mesh.positions.swap(next);
    }
}

} // namespace vox::render
