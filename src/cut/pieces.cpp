#include "cut/pieces.hpp"

#include "core/union_find.hpp"

#include <algorithm>

namespace vox::cut {

std::vector<std::uint32_t> element_pieces(const fem::HexModel& model)
{
    UnionFind nodes(model.node_count()); // the corners of every element joined
    for (const fem::HexElement& el : model.elements())
        for (int c = 1; c < 8; ++c) nodes.unite(el.dof_node[c], el.dof_node[0]);
    // Two levels: a border node moves with the coarse nodes it is tied to.
    for (const grid::MixedLevels::Tie& t : model.ties())
        for (std::size_t c = 0; c < 8; ++c)
            if (t.weights[c] != 0.0) nodes.unite(t.node, t.masters[c]);
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

std::vector<unsigned char> unheld_elements(const fem::HexModel& model, const std::vector<unsigned char>& held, std::size_t& count)
{
    const std::vector<std::uint32_t> piece = element_pieces(model);
    std::vector<unsigned char> reached(piece.empty() ? 0 : *std::max_element(piece.begin(), piece.end()) + 1, 0);
    for (std::uint32_t e = 0; e < model.elements().size(); ++e)
        for (std::uint32_t n : model.elements()[e].dof_node)
            if (held[n]) reached[piece[e]] = 1;
    count = static_cast<std::size_t>(std::count(reached.begin(), reached.end(), 0));
    std::vector<unsigned char> out(piece.size());
    for (std::size_t e = 0; e < piece.size(); ++e) out[e] = reached[piece[e]] ? 0 : 1;
    return out;
}

} // namespace vox::cut
