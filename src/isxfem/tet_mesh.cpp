#include "isxfem/tet_mesh.hpp"

#include <Eigen/Geometry>
#include <Eigen/LU>

#include <algorithm>
#include <map>
#include <stdexcept>

namespace vox::isxfem {

double signed_volume(const std::array<Eigen::Vector3d, 4>& x)
{
    return (x[1] - x[0]).cross(x[2] - x[0]).dot(x[3] - x[0]) / 6.0;
}

std::array<double, 4> barycentric(const TetMesh& mesh, std::size_t t, const Eigen::Vector3d& x)
{
    const auto c = mesh.corners(t);
    Eigen::Matrix3d j;
    for (int k = 0; k < 3; ++k) j.col(k) = c[static_cast<std::size_t>(k + 1)] - c[0];
    const Eigen::Vector3d l = j.inverse() * (x - c[0]);
    return {1.0 - l.sum(), l.x(), l.y(), l.z()};
}

std::array<double, 4> clamped(std::array<double, 4> bary)
{
    double sum = 0.0;
    for (double& b : bary) sum += (b = std::max(b, 0.0));
    if (!(sum > 0.0)) return {0.25, 0.25, 0.25, 0.25};
    for (double& b : bary) b /= sum;
    return bary;
}

std::vector<std::array<std::int32_t, 4>> face_neighbours(const TetMesh& mesh)
{
    std::vector<std::array<std::int32_t, 4>> out(mesh.tets.size(), {-1, -1, -1, -1});
    std::map<std::array<std::uint32_t, 3>, std::pair<std::int32_t, int>> open; // sorted face -> (tet, corner opposite)
    for (std::size_t t = 0; t < mesh.tets.size(); ++t)
        for (int c = 0; c < 4; ++c) {
            std::array<std::uint32_t, 3> face{};
            for (int k = 0, m = 0; k < 4; ++k)
                if (k != c) face[static_cast<std::size_t>(m++)] = mesh.tets[t][static_cast<std::size_t>(k)];
            std::sort(face.begin(), face.end());
            const auto [it, fresh] = open.try_emplace(face, static_cast<std::int32_t>(t), c);
            if (fresh) continue;
            out[t][static_cast<std::size_t>(c)] = it->second.first;
            out[static_cast<std::size_t>(it->second.first)][static_cast<std::size_t>(it->second.second)] = static_cast<std::int32_t>(t);
            open.erase(it);
        }
    return out;
}

std::pair<std::size_t, std::array<double, 4>> walk_to(const TetMesh& mesh, const std::vector<std::array<std::int32_t, 4>>& neighbours,
                                                      std::size_t start, const Eigen::Vector3d& x)
{
    std::size_t t = start;
    std::array<double, 4> b = barycentric(mesh, t, x);
    for (int step = 0; step < 64; ++step) {
        const auto lowest = static_cast<std::size_t>(std::min_element(b.begin(), b.end()) - b.begin());
        if (b[lowest] >= -1e-12 || neighbours[t][lowest] < 0) break;
        t = static_cast<std::size_t>(neighbours[t][lowest]);
        b = barycentric(mesh, t, x);
    }
    return {t, clamped(b)};
}

TetMesh cube_lattice(const Eigen::Vector3i& cells, double h)
{
    if ((cells.array() < 1).any() || !(h > 0.0)) throw std::invalid_argument("cube_lattice: needs at least one cell and h > 0");
    TetMesh mesh;
    const Eigen::Vector3i n = cells + Eigen::Vector3i::Ones();
    auto id = [&](int i, int j, int k) { return static_cast<std::uint32_t>((k * n.y() + j) * n.x() + i); };
    for (int k = 0; k < n.z(); ++k)
        for (int j = 0; j < n.y(); ++j)
            for (int i = 0; i < n.x(); ++i) mesh.nodes.emplace_back(i * h, j * h, k * h);
    for (int k = 0; k < cells.z(); ++k)
        for (int j = 0; j < cells.y(); ++j)
            for (int i = 0; i < cells.x(); ++i) {
                // The path (0,0,0) -> (1,1,1) through one axis at a time, in each of the 6 orders.
                std::array<int, 3> order{0, 1, 2};
                do {
                    Eigen::Vector3i c(i, j, k);
                    std::array<std::uint32_t, 4> t{};
                    t[0] = id(c.x(), c.y(), c.z());
                    for (int s = 0; s < 3; ++s) {
                        c[order[static_cast<std::size_t>(s)]] += 1;
                        t[static_cast<std::size_t>(s + 1)] = id(c.x(), c.y(), c.z());
                    }
                    if (signed_volume({mesh.nodes[t[0]], mesh.nodes[t[1]], mesh.nodes[t[2]], mesh.nodes[t[3]]}) < 0.0) std::swap(t[2], t[3]);
                    mesh.tets.push_back(t);
                } while (std::next_permutation(order.begin(), order.end()));
            }
    return mesh;
}

} // namespace vox::isxfem
