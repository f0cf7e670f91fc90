#include "grid/mixed_levels.hpp"

#include "grid/hex8.hpp"

#include <stdexcept>
#include <string>

namespace vox::grid {

std::uint32_t ancestor(const BranchedGrid& grid, int from, std::uint32_t e, int to)
{
    for (int k = from + 1; k <= to; ++k) e = grid.level(k).parent[e];
    return e;
}

MixedLevels::MixedLevels(const BranchedGrid& grid, int fine, int coarse, const std::function<bool(std::uint32_t)>& refine)
    : m_fine(fine), m_coarse(coarse)
{
    if (fine < 1 || fine >= coarse || coarse > grid.max_level())
        throw std::invalid_argument("mixed levels: need 1 <= fine < coarse <= " + std::to_string(grid.max_level()) + ", got fine " +
                                    std::to_string(fine) + ", coarse " + std::to_string(coarse));
    const Level& fl = grid.level(fine);
    const Level& cl = grid.level(coarse);
    std::vector<unsigned char> refined(cl.elements.size(), 0);
    for (std::uint32_t e = 0; e < cl.elements.size(); ++e) refined[e] = cl.elements[e].alive && refine(e);

    // Mixed numbering: the fine nodes of fine elements inside the region, then the coarse nodes of
    // coarse elements outside it.
    std::vector<std::uint32_t> fine_id(fl.node_users.size(), no_index), coarse_id(cl.node_users.size(), no_index);
    const std::vector<Eigen::Vector3d> fine_rest = grid.rest_node_positions(fine), coarse_rest = grid.rest_node_positions(coarse);
    auto number = [&](std::vector<std::uint32_t>& ids, std::uint32_t n, int level, const std::vector<Eigen::Vector3d>& rest) {
        if (ids[n] == no_index) {
            ids[n] = static_cast<std::uint32_t>(m_node_level.size());
            m_node_level.push_back(level);
            m_grid_node.push_back(n);
            m_rest_mm.push_back(rest[n]);
        }
        return ids[n];
    };
    // Per fine node: a fine element outside the region using it (the material it connects to there).
    std::vector<std::uint32_t> outside_user(fl.node_users.size(), no_index);
    for (std::uint32_t f = 0; f < fl.elements.size(); ++f) {
        const grid::Element& g = fl.elements[f];
        if (!g.alive) continue;
        if (refined[ancestor(grid, fine, f, coarse)]) {
            Element el{fine, f, {}};
            for (int c = 0; c < 8; ++c) el.nodes[static_cast<std::size_t>(c)] = number(fine_id, g.nodes[static_cast<std::size_t>(c)], fine, fine_rest);
            m_elements.push_back(el);
        } else {
            for (std::uint32_t n : g.nodes) outside_user[n] = f;
        }
    }
    m_fine_elements = m_elements.size();
    for (std::uint32_t e = 0; e < cl.elements.size(); ++e) {
        if (!cl.elements[e].alive || refined[e]) continue;
        Element el{coarse, e, {}};
        for (int c = 0; c < 8; ++c) el.nodes[static_cast<std::size_t>(c)] = number(coarse_id, cl.elements[e].nodes[static_cast<std::size_t>(c)], coarse, coarse_rest);
        m_elements.push_back(el);
    }

    // The border: fine nodes of the region shared with fine elements outside it.
    const double ratio = static_cast<double>(1 << (coarse - fine));
    std::vector<unsigned char> tied(fl.node_users.size(), 0); // a node sits in several region elements: tied once
    for (std::size_t i = 0; i < m_fine_elements; ++i) {
        const grid::Element& g = fl.elements[m_elements[i].element];
        for (int c = 0; c < 8; ++c) {
            const std::uint32_t n = g.nodes[static_cast<std::size_t>(c)];
            if (outside_user[n] == no_index || tied[n]) continue;
            tied[n] = 1;
            Tie tie;
            tie.node = fine_id[n];
            tie.coarse_element = ancestor(grid, fine, outside_user[n], coarse);
            const grid::Element& ce = cl.elements[tie.coarse_element];
            // The node's place in the coarse cell, 0..1 per axis, in whole steps of the fine cells.
            const Eigen::Vector3d t = ((g.cell.cast<double>() + Eigen::Vector3d(c & 1, (c >> 1) & 1, (c >> 2) & 1)) -
                                       ce.cell.cast<double>() * ratio) /
                                      ratio;
            for (int k = 0; k < 8; ++k) {
                tie.masters[static_cast<std::size_t>(k)] = coarse_id[ce.nodes[static_cast<std::size_t>(k)]];
                tie.weights[static_cast<std::size_t>(k)] = hex8_shape(k, t);
            }
            m_ties.push_back(tie);
        }
    }
}

} // namespace vox::grid
