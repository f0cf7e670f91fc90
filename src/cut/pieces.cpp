#include "cut/pieces.hpp"

#include "core/union_find.hpp"

#include <algorithm>

namespace vox::cut {

std::vector<std::uint32_t> element_pieces(const fem::HexModel& model)
{
    UnionFind nodes(model.node_count()); // the corners of every element joined
    for (const fem::HexElement& el : model.elements())
        for (int c = 1; c < 8; ++c) nodes.unite(el.dof_node[c], el.dof_node[0]);
    std::vector<std::uint32_t> number(model.node_count(), ~0u), out;
    std::uint32_t next = 0;
    for (const fem::HexElement& el : model.elements()) {
        std::uint32_t& id = number[nodes.find(el.dof_node[0])];
        if (id == ~0u) id = next++;
        out.push_back(id);
    }
    return out;
}

std::size_t piece_count(const fem::HexModel& model)
{
    const std::vector<std::uint32_t> pieces = element_pieces(model);
    return pieces.empty() ? 0 : *std::max_element(pieces.begin(), pieces.end()) + 1;
}

} // namespace vox::cut
