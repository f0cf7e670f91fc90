#include "fem/hex_model.hpp"

#include "core/error.hpp"
#include "grid/hex8.hpp"

#include <algorithm>
#include <numeric>

namespace vox::fem {

HexModel::HexModel(const grid::BranchedGrid& grid, int level) : m_level(level)
{
    if (level < 1 || level > grid.max_level())
        throw InputError("the simulated level must be 1 .. " + std::to_string(grid.max_level()) + ", got " +
                         std::to_string(level));
    const grid::Level& lv = grid.level(level);
    const Eigen::Matrix4d& t = grid.voxels().index_to_world();
    const Eigen::Vector3d h = grid.voxels().voxel_size_m(); // voxel edges, m
    const Eigen::Vector3d spacing_mm = h * 1e3;
    m_frame = t.topLeftCorner<3, 3>() * spacing_mm.cwiseInverse().asDiagonal();
    const double cell = static_cast<double>(1 << level);

    // Dense numbering of the nodes the alive elements use.
    m_dense_node.assign(lv.node_users.size(), grid::no_index);
    std::size_t alive = 0, partial = 0;
    for (std::uint32_t e = 0; e < lv.elements.size(); ++e) {
        if (!lv.elements[e].alive) continue;
        ++alive;
        partial += !grid.is_full(level, e);
        for (std::uint32_t n : lv.elements[e].nodes)
            if (m_dense_node[n] == grid::no_index) {
                m_dense_node[n] = static_cast<std::uint32_t>(m_grid_node.size());
                m_grid_node.push_back(n);
            }
    }
    const auto grid_rest = grid.rest_node_positions(level);
    m_rest_world.resize(m_grid_node.size());
    for (std::size_t i = 0; i < m_grid_node.size(); ++i) m_rest_world[i] = grid_rest[m_grid_node[i]] * 1e-3;
    m_nodal_mass.assign(m_grid_node.size(), 0.0);

    for (const grid::VoxelMaterial& m : grid.materials())
        m_full_stiffness.push_back(cell * grid::hex8_stiffness(h, m.lame));
    m_partial_stiffness.reserve(partial); // elements point into it: no reallocation allowed
    m_elements.reserve(alive);
    for (std::uint32_t e = 0; e < lv.elements.size(); ++e) {
        const grid::Element& g = lv.elements[e];
        if (!g.alive) continue;
        HexElement el;
        el.grid_element = e;
        for (int c = 0; c < 8; ++c) el.dof_node[c] = m_dense_node[g.nodes[c]];
        if (grid.is_full(level, e)) {
            el.stiffness = &m_full_stiffness[static_cast<std::size_t>(g.content[0].material)];
        } else {
            m_partial_stiffness.push_back(grid.stiffness(level, e));
            el.stiffness = &m_partial_stiffness.back();
        }
        el.mass = grid.mass(level, e);
        for (int c = 0; c < 8; ++c) {
            el.rest.segment<3>(3 * c) = grid::BranchedGrid::cell_corner_index(g.cell, level, c).cwiseProduct(h);
            m_nodal_mass[el.dof_node[c]] += el.mass.row(c).sum();
        }
        // Centroid of the element's material (first moments over zeroth, summed over materials),
        // in the cell's local coordinates t in [0, 1]^3.
        double q0 = 0.0;
        Eigen::Vector3d q1 = Eigen::Vector3d::Zero();
        for (const grid::MaterialMoments& m : g.content) {
            q0 += static_cast<double>(m.moments[0]);
            q1 += Eigen::Vector3d(static_cast<double>(m.moments[1]), static_cast<double>(m.moments[3]),
                                  static_cast<double>(m.moments[9]));
        }
        const Eigen::Vector3d centre = q1 / q0 / cell;
        for (int c = 0; c < 8; ++c) {
            const int bx = c & 1, by = (c >> 1) & 1, bz = (c >> 2) & 1;
            auto f = [](int bit, double x) { return bit ? x : 1.0 - x; };
            auto df = [](int bit) { return bit ? 1.0 : -1.0; };
            el.gradient(c, 0) = df(bx) * f(by, centre.y()) * f(bz, centre.z()) / (cell * h.x());
            el.gradient(c, 1) = f(bx, centre.x()) * df(by) * f(bz, centre.z()) / (cell * h.y());
            el.gradient(c, 2) = f(bx, centre.x()) * f(by, centre.y()) * df(bz) / (cell * h.z());
        }
        m_elements.push_back(el);
    }
    double density = 0.0;
    for (const grid::VoxelMaterial& m : grid.materials()) density = std::max(density, m.density_kg_m3);
    const double floor = 1e-3 * density * (cell * cell * cell) * h.prod() / 8.0;
    m_added_mass.assign(m_nodal_mass.size(), 0.0);
    for (std::size_t n = 0; n < m_nodal_mass.size(); ++n)
        if (m_nodal_mass[n] < floor) {
            m_added_mass[n] = floor - m_nodal_mass[n];
            m_nodal_mass[n] = floor;
        }
}

double HexModel::total_mass() const { return std::accumulate(m_nodal_mass.begin(), m_nodal_mass.end(), 0.0); }

} // namespace vox::fem
