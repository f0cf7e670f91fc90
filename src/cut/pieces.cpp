#include "cut/pieces.hpp"

#include <algorithm>
#include <numeric>

namespace vox::cut {

std::vector<std::uint32_t> element_pieces(const fem::HexModel& model)
{
    // Union-find over nodes, joining the corners of every element.
    std::vector<std::uint32_t> parent(model.node_count());
    std::iota(parent.begin(), parent.end(), 0u);
    auto root = [&](std::uint32_t n) {
        while (parent[n] != n) n = parent[n] = parent[parent[n]];
        return n;
    };
    for (const fem::HexElement& el : model.elements())
        for (int c = 1; c < 8; ++c) parent[root(el.dof_node[c])] = root(el.dof_node[0]);
    std::vector<std::uint32_t> number(model.node_count(), ~0u), out;
    std::uint32_t next = 0;
    for (const fem::HexElement& el : model.elements()) {
        std::uint32_t& id = number[root(el.dof_node[0])];
        if (id == ~0u) id = next++;
        out.push_back(id);
    }
    return out;
}

std::size_t piece_count(const fem::HexModel& model)
{
    const std::vector<std::uint32_t> pieces = element_pieces(model);
    std::uint32_t most = 0;
    for (std::uint32_t p : pieces) most = std::max(most, p + 1);
    return most;
}

} // namespace vox::cut
