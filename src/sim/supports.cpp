#include "sim/supports.hpp"

#include "grid/hex8.hpp"
#include "io/box.hpp"

#include <Eigen/Geometry>

namespace vox::sim {

BoxMaterial::Held BoxMaterial::measure(const grid::BranchedGrid& grid, int level, std::uint32_t element) const
{
    const grid::FineVoxels& fine = grid.voxels();
    Held out;
    if (level == 0) { // the voxel is the element: all eight corners, an eighth of it each
        if (fine.alive(element) && io::in_box(fine.world_mm(fine.coord(element).cast<double>()), m_lo, m_hi)) {
            out.voxels = 1;
            out.corners = 0xff;
            out.weight.fill(0.125);
        }
        return out;
    }
    const grid::Element& g = grid.level(level).elements[element];
    // The cell's corners lie half a voxel beyond its outer voxels' centres: a cell whose box misses
    // the support's grown by that much holds none of its voxels.
    const Eigen::Vector3d reach = 0.5e3 * fine.voxel_size_m();
    Eigen::AlignedBox3d cell;
    for (int c = 0; c < 8; ++c) cell.extend(fine.world_mm(grid::BranchedGrid::cell_corner_index(g.cell, level, c)));
    if (!cell.intersects(Eigen::AlignedBox3d(m_lo - reach, m_hi + reach))) return out;
    const Eigen::Vector3d corner0 = grid::BranchedGrid::cell_corner_index(g.cell, level, 0);
    const double size = static_cast<double>(1 << level);
    for (std::uint32_t v : g.voxels) {
        if (!fine.alive(v)) continue;
        const Eigen::Vector3d centre = fine.coord(v).cast<double>();
        if (!io::in_box(fine.world_mm(centre), m_lo, m_hi)) continue;
        const Eigen::Vector3d t = (centre - corner0) / size; // in (0, 1) per axis
        ++out.voxels;
        // A voxel centre never lies on a cell's mid-plane above level 0 (centres sit half a voxel
        // off it), so the nearest corner is unique.
        out.corners |= static_cast<std::uint8_t>(1u << ((t.x() > 0.5 ? 1 : 0) | (t.y() > 0.5 ? 2 : 0) | (t.z() > 0.5 ? 4 : 0)));
        for (int c = 0; c < 8; ++c) out.weight[static_cast<std::size_t>(c)] += grid::hex8_shape(c, t);
    }
    return out;
}

void BoxMaterial::update(const grid::BranchedGrid& grid, int level, const std::vector<unsigned char>* changed)
{
    const std::size_t count = level == 0 ? grid.voxels().slots() : grid.level(level).elements.size();
    if (level == 0) changed = nullptr; // level-0 models are built afresh after every change
    std::vector<Held>& by_element = m_by_level.at(static_cast<std::size_t>(level));
    by_element.resize(count);
    for (std::uint32_t e = 0; e < count; ++e) {
        if (changed && !(e < changed->size() && (*changed)[e])) continue;
        const bool alive = level == 0 || grid.level(level).elements[e].alive;
        by_element[e] = alive ? measure(grid, level, e) : Held{};
    }
}

std::size_t BoxMaterial::voxel_count(const fem::HexModel& model) const
{
    std::size_t n = 0;
    for (const fem::HexElement& el : model.elements()) n += held(el).voxels;
    return n;
}

std::vector<std::uint32_t> BoxMaterial::supported_nodes(const fem::HexModel& model) const
{
    std::vector<unsigned char> holds(model.node_count(), 0);
    for (const fem::HexElement& el : model.elements()) {
        const std::uint8_t corners = held(el).corners;
        for (std::size_t c = 0; c < 8; ++c)
            if (corners & (1u << c)) holds[el.dof_node[c]] = 1;
    }
    for (const grid::MixedLevels::Tie& t : model.ties()) {
        if (!holds[t.node]) continue;
        holds[t.node] = 0;
        for (std::size_t c = 0; c < 8; ++c)
            if (t.weights[c] != 0.0) holds[t.masters[c]] = 1;
    }
    std::vector<std::uint32_t> out;
    for (std::uint32_t n = 0; n < holds.size(); ++n)
        if (holds[n]) out.push_back(n);
    return out;
}

std::vector<std::pair<std::uint32_t, double>> BoxMaterial::load_shares(const fem::HexModel& model) const
{
    const std::size_t voxels = voxel_count(model);
    std::vector<double> share(model.node_count(), 0.0);
    for (const fem::HexElement& el : model.elements()) {
        const Held& h = held(el);
        if (h.voxels == 0) continue;
        for (std::size_t c = 0; c < 8; ++c) share[el.dof_node[c]] += h.weight[c] / static_cast<double>(voxels);
    }
    std::vector<std::pair<std::uint32_t, double>> out;
    for (std::uint32_t n = 0; n < share.size(); ++n)
        if (share[n] > 0.0) out.emplace_back(n, share[n]);
    return out;
}

} // namespace vox::sim
