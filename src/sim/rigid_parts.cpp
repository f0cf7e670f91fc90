#include "sim/rigid_parts.hpp"

#include "io/scene_object.hpp"

#include <algorithm>

namespace vox::sim {

std::vector<unsigned char> rigid_materials(const io::Scene& scene)
{
    std::vector<unsigned char> out;
    for (const io::Material& m : io::material_table(scene).scene_materials) out.push_back(m.rigid ? 1 : 0);
    return out;
}

std::vector<RigidContent> rigid_content(const grid::BranchedGrid& grid, const fem::HexModel& model,
                                        const std::vector<unsigned char>& rigid_material)
{
    std::vector<RigidContent> out(model.elements().size());
    if (std::find(rigid_material.begin(), rigid_material.end(), 1) == rigid_material.end()) return out;
    const grid::FineVoxels& voxels = grid.voxels();
    const auto rigid_voxel = [&](std::uint32_t v) { return rigid_material[static_cast<std::size_t>(voxels.material(v))] != 0; };
    for (std::uint32_t e = 0; e < model.elements().size(); ++e) {
        const std::uint32_t ge = model.elements()[e].grid_element;
        const int level = model.elements()[e].level; // a model of two levels has both
        const double half = 0.5 * static_cast<double>(1 << level); // voxels
        RigidContent& r = out[e];
        if (level == 0) { // the element is the voxel
            r.corners = rigid_voxel(ge) ? 0xFF : 0;
            r.soft = !rigid_voxel(ge);
            continue;
        }
        const grid::Element& g = grid.level(level).elements[ge];
        const Eigen::Vector3d origin = grid::BranchedGrid::cell_corner_index(g.cell, level, 0);
        for (std::uint32_t v : g.voxels) {
            if (!rigid_voxel(v)) {
                r.soft = true;
                continue;
            }
            const Eigen::Vector3d local = voxels.coord(v).cast<double>() - origin; // voxel centres: 0.5 .. 2^level - 0.5
            const int c = (local.x() > half ? 1 : 0) | (local.y() > half ? 2 : 0) | (local.z() > half ? 4 : 0);
            r.corners = static_cast<std::uint8_t>(r.corners | (1u << c));
        }
    }
    return out;
}

std::vector<unsigned char> anchoring_nodes(const fem::HexModel& model, const std::vector<std::uint32_t>& piece,
                                           const std::vector<RigidContent>& rigid, std::vector<unsigned char> constrained)
{
    if (std::none_of(rigid.begin(), rigid.end(), [](const RigidContent& r) { return r.corners != 0; })) return constrained;
    std::vector<unsigned char> soft(piece.empty() ? 0 : *std::max_element(piece.begin(), piece.end()) + 1, 0);
    for (std::uint32_t e = 0; e < model.elements().size(); ++e)
        if (rigid[e].soft || rigid[e].corners == 0) soft[piece[e]] = 1;
    for (std::uint32_t e = 0; e < model.elements().size(); ++e)
        if (rigid[e].corners && soft[piece[e]])
            for (int c = 0; c < 8; ++c)
                if (rigid[e].corners & (1u << c)) constrained[model.elements()[e].dof_node[static_cast<std::size_t>(c)]] = 1;
    return constrained;
}

RigidParts rigid_parts(const fem::HexModel& model, const std::vector<std::uint32_t>& piece, const std::vector<RigidContent>& rigid,
                       const std::vector<unsigned char>& held, bool unheld_rigid)
{
    RigidParts out;
    out.anchored.assign(model.node_count(), 0);
    out.rigid_elements = static_cast<std::size_t>(std::count_if(rigid.begin(), rigid.end(), [](const RigidContent& r) { return r.corners != 0; }));
    if (out.rigid_elements == 0 && !unheld_rigid) return out;
    const std::size_t pieces = piece.empty() ? 0 : *std::max_element(piece.begin(), piece.end()) + 1;
    std::vector<unsigned char> reached(pieces, 0), all_rigid(pieces, 1);
    for (std::uint32_t e = 0; e < model.elements().size(); ++e) {
        if (rigid[e].soft || rigid[e].corners == 0) all_rigid[piece[e]] = 0;
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
            for (int c = 0; c < 8; ++c)
                if (rigid[e].corners & (1u << c)) out.anchored[model.elements()[e].dof_node[static_cast<std::size_t>(c)]] = 1;
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
