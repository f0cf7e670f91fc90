#include "sim/rigid_parts.hpp"

#include "cut/pieces.hpp"
#include "io/scene_object.hpp"

#include <algorithm>

namespace vox::sim {

std::vector<unsigned char> rigid_materials(const io::Scene& scene)
{
    std::vector<unsigned char> out;
    for (const io::Material& m : io::material_table(scene).scene_materials) out.push_back(m.rigid ? 1 : 0);
    return out;
}

std::vector<unsigned char> rigid_elements(const grid::BranchedGrid& grid, const fem::HexModel& model,
                                          const std::vector<unsigned char>& rigid_material)
{
    std::vector<unsigned char> out(model.elements().size(), 0);
    if (std::find(rigid_material.begin(), rigid_material.end(), 1) == rigid_material.end()) return out;
    const auto rigid_voxel = [&](std::uint32_t v) { return rigid_material[static_cast<std::size_t>(grid.voxels().material(v))] != 0; };
    for (std::uint32_t e = 0; e < model.elements().size(); ++e) {
        const std::uint32_t ge = model.elements()[e].grid_element;
        if (model.level() == 0) {
            out[e] = rigid_voxel(ge) ? 1 : 0; // level 0: the element is the voxel
            continue;
        }
        const auto& voxels = grid.level(model.level()).elements[ge].voxels;
        out[e] = std::any_of(voxels.begin(), voxels.end(), rigid_voxel) ? 1 : 0;
    }
    return out;
}

std::vector<unsigned char> anchoring_nodes(const fem::HexModel& model, const std::vector<unsigned char>& rigid_element,
                                           std::vector<unsigned char> constrained)
{
    if (std::find(rigid_element.begin(), rigid_element.end(), 1) == rigid_element.end()) return constrained;
    const std::vector<std::uint32_t> piece = cut::element_pieces(model);
    std::vector<unsigned char> soft(piece.empty() ? 0 : *std::max_element(piece.begin(), piece.end()) + 1, 0);
    for (std::uint32_t e = 0; e < model.elements().size(); ++e)
        if (!rigid_element[e]) soft[piece[e]] = 1;
    for (std::uint32_t e = 0; e < model.elements().size(); ++e)
        if (rigid_element[e] && soft[piece[e]])
            for (std::uint32_t n : model.elements()[e].dof_node) constrained[n] = 1;
    return constrained;
}

RigidParts rigid_parts(const fem::HexModel& model, const std::vector<unsigned char>& rigid_element,
                       const std::vector<unsigned char>& held, bool unheld_rigid)
{
    RigidParts out;
    out.anchored.assign(model.node_count(), 0);
    out.rigid_elements = static_cast<std::size_t>(std::count(rigid_element.begin(), rigid_element.end(), 1));
    if (out.rigid_elements == 0 && !unheld_rigid) return out;
    const std::vector<std::uint32_t> piece = cut::element_pieces(model);
    const std::size_t pieces = piece.empty() ? 0 : *std::max_element(piece.begin(), piece.end()) + 1;
    std::vector<unsigned char> reached(pieces, 0), all_rigid(pieces, 1);
    for (std::uint32_t e = 0; e < model.elements().size(); ++e) {
        if (!rigid_element[e]) all_rigid[piece[e]] = 0;
        for (std::uint32_t n : model.elements()[e].dof_node)
            if (held[n]) reached[piece[e]] = 1;
    }
    // Pieces moving as bodies get numbers in order of their lowest element.
    std::vector<std::int32_t> body(pieces, -1);
    std::vector<unsigned char> listed(model.node_count(), 0); // a node belongs to one piece only
    for (std::uint32_t e = 0; e < model.elements().size(); ++e) {
        const std::uint32_t p = piece[e];
        const bool moves = !reached[p] && (unheld_rigid || all_rigid[p]);
        if (!moves) {
            if (rigid_element[e])
                for (std::uint32_t n : model.elements()[e].dof_node) out.anchored[n] = 1;
            continue;
        }
        if (body[p] < 0) {
            body[p] = static_cast<std::int32_t>(out.bodies.size());
            out.bodies.emplace_back();
        }
        for (std::uint32_t n : model.elements()[e].dof_node)
            if (!listed[n]++) out.bodies[static_cast<std::size_t>(body[p])].push_back(n);
    }
    return out;
}

} // namespace vox::sim
