#include "isxfem/grid_tets.hpp"

#include <Eigen/LU>

#include <algorithm>
#include <cmath>
#include <numeric>

namespace vox::isxfem {
namespace {

constexpr double k_fill_floor = 1e-3;

/// The Kuhn tetrahedra (0 .. 5, in the order of std::next_permutation over the axes) of the unit
/// cube holding local point t: those whose axis order sorts t's coordinates descending. A point
/// on the planes between them (equal coordinates, as many voxel centres are) belongs to each in
/// equal shares, so a full cell gives each of its six tetrahedra the same material.
void add_kuhn_shares(const Eigen::Vector3d& t, double amount, std::array<double, 6>& shares)
{
    std::array<int, 3> order{0, 1, 2};
    std::array<bool, 6> holds{};
    int count = 0, index = 0;
    do {
        holds[static_cast<std::size_t>(index)] = t[order[0]] >= t[order[1]] && t[order[1]] >= t[order[2]];
        count += holds[static_cast<std::size_t>(index)];
        ++index;
    } while (std::next_permutation(order.begin(), order.end()));
    for (std::size_t k = 0; k < 6; ++k)
        if (holds[k]) shares[k] += amount / count;
}

} // namespace

GridTets tets_from_model(const grid::BranchedGrid& grid, const fem::HexModel& model)
{
    GridTets out;
    out.mesh.nodes = model.rest_positions();
    const int level = model.level();
    const auto& grid_materials = grid.materials();
    for (const fem::HexElement& el : model.elements()) {
        // Material per tetrahedron: shares of fine voxel centres, per material.
        std::array<std::vector<double>, 6> count;
        for (auto& c : count) c.assign(grid_materials.size(), 0.0);
        double capacity = 1.0 / 6.0; // voxels a tetrahedron of the cell holds
        if (level == 0) {
            for (auto& c : count) c[static_cast<std::size_t>(el.material)] = capacity;
        } else {
            const grid::Element& ge = grid.level(level).elements[el.grid_element];
            const double size = static_cast<double>(1 << level);
            capacity = size * size * size / 6.0;
            const Eigen::Vector3d corner0 = grid::BranchedGrid::cell_corner_index(ge.cell, level, 0);
            for (std::uint32_t v : ge.voxels) {
                std::array<double, 6> shares{};
                add_kuhn_shares((grid.voxels().coord(v).cast<double>() - corner0) / size, 1.0, shares);
                for (std::size_t k = 0; k < 6; ++k) count[k][static_cast<std::size_t>(grid.voxels().material(v))] += shares[k];
            }
        }
        std::array<int, 3> order{0, 1, 2};
        int p = 0;
        do {
            // The path corner 0 -> +order[0] -> +order[1] -> corner 7 (corner bits: +x 1, +y 2, +z 4).
            std::array<std::uint32_t, 4> t{};
            int corner = 0;
            t[0] = el.dof_node[0];
            for (int s = 0; s < 3; ++s) {
                corner |= 1 << order[static_cast<std::size_t>(s)];
                t[static_cast<std::size_t>(s + 1)] = el.dof_node[static_cast<std::size_t>(corner)];
            }
            if (signed_volume({out.mesh.nodes[t[0]], out.mesh.nodes[t[1]], out.mesh.nodes[t[2]], out.mesh.nodes[t[3]]}) < 0.0)
                std::swap(t[2], t[3]); // a mirroring scan transform
            out.mesh.tets.push_back(t);
            const std::vector<double>& c = count[static_cast<std::size_t>(p)];
            const double held = std::accumulate(c.begin(), c.end(), 0.0);
            const double fill = std::clamp(held / capacity, k_fill_floor, 1.0);
            grid::ElasticMaterial m{{0.0, 0.0}, 0.0};
            const std::size_t dominant = held > 0.0 ? static_cast<std::size_t>(std::max_element(c.begin(), c.end()) - c.begin())
                                                    : static_cast<std::size_t>(el.material);
            for (std::size_t k = 0; k < c.size(); ++k) {
                // Shares of the held material (an empty one: the element's own material).
                const double share = held > 0.0 ? c[k] / held : (k == dominant ? 1.0 : 0.0);
                m.lame.lambda += fill * share * grid_materials[k].lame.lambda;
                m.lame.mu += fill * share * grid_materials[k].lame.mu;
                m.density_kg_m3 += fill * share * grid_materials[k].density_kg_m3;
            }
            out.material.push_back(static_cast<std::uint32_t>(out.materials.size()));
            out.materials.push_back(m);
            out.fill.push_back(fill);
            ++p;
        } while (std::next_permutation(order.begin(), order.end()));
    }
    return out;
}

std::pair<std::size_t, std::array<double, 4>> locate(const TetMesh& mesh, std::size_t element, const Eigen::Vector3d& x)
{
    std::size_t best = GridTets::first_tet(element);
    std::array<double, 4> best_l{0.25, 0.25, 0.25, 0.25};
    double best_min = -INFINITY;
    for (std::size_t t = GridTets::first_tet(element); t < GridTets::first_tet(element) + 6; ++t) {
        const std::array<double, 4> bary = barycentric(mesh, t, x);
        const double lowest = *std::min_element(bary.begin(), bary.end());
        if (lowest > best_min) {
            best_min = lowest;
            best = t;
            best_l = bary;
        }
    }
    // A point on the cell's boundary may sit a rounding error outside: clamp that. A point
    // farther out (a smoothed surface vertex, which may leave its element a little, as the
    // branched grid's trilinear coordinates may leave [0, 1]) keeps its coordinates: they still
    // reproduce any affine motion of the tetrahedron exactly.
    return {best, best_min > -1e-9 ? clamped(best_l) : best_l};
}

} // namespace vox::isxfem
