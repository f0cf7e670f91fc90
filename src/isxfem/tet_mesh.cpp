#include "isxfem/tet_mesh.hpp"

#include <Eigen/Geometry>

#include <algorithm>
#include <stdexcept>

namespace vox::isxfem {

double signed_volume(const std::array<Eigen::Vector3d, 4>& x)
{
    return (x[1] - x[0]).cross(x[2] - x[0]).dot(x[3] - x[0]) / 6.0;
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
