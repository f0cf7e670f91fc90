#include "cut/surface_contact.hpp"

#include "grid/hex8.hpp"

#include <algorithm>
#include <unordered_map>

namespace vox::cut {

SurfaceContact touch_surface(const ModelSurface& surface, const std::vector<Eigen::Vector3d>& node_positions,
                             const contact::PlacedShape& tool, const contact::ContactParameters& parameters)
{
    SurfaceContact out;
    const fem::HexModel& model = surface.model();
    const Eigen::AlignedBox3d reach = tool.world_bounds(parameters.margin_mm);
    // Candidate points: vertices of elements whose deformed corners' box meets the reach, kept
    // when inside the outer shape. (Surface vertices lie inside their element's cell, and a
    // trilinear map keeps points inside its corners' box.)
    std::vector<std::uint32_t> inside;
    std::vector<Eigen::Vector3d> inside_mm;
    for (std::uint32_t e = 0; e < model.elements().size(); ++e) {
        Eigen::AlignedBox3d box;
        box.setEmpty();
        for (std::uint32_t n : model.elements()[e].dof_node) box.extend(1e3 * node_positions[n]);
        if (!box.intersects(reach)) continue;
        for (std::uint32_t v : surface.element_vertices(e)) {
            const Eigen::Vector3d p = surface.vertex_mm(v, node_positions);
            if (!reach.contains(p) || tool.signed_distance(p) >= parameters.margin_mm) continue;
            inside.push_back(v);
            inside_mm.push_back(p);
        }
    }
    if (inside.empty()) return out;
    // Each point carries a third of the deformed area of the triangles around it.
    std::unordered_map<std::uint32_t, Eigen::Vector3d> known;
    for (std::size_t i = 0; i < inside.size(); ++i) known.emplace(inside[i], inside_mm[i]);
    auto position = [&](std::uint32_t v) {
        const auto found = known.find(v);
        if (found != known.end()) return found->second;
        return known.emplace(v, surface.vertex_mm(v, node_positions)).first->second;
    };
    // and the area-weighted mean of their normals.
    std::vector<double> areas(inside.size(), 0.0);
    std::vector<Eigen::Vector3d> normals(inside.size(), Eigen::Vector3d::Zero());
    const auto& triangles = surface.embedded().triangles();
    for (std::size_t i = 0; i < inside.size(); ++i) {
        for (std::uint32_t t : surface.vertex_triangles(inside[i])) {
            const auto& tri = triangles[t];
            const Eigen::Vector3d a = position(tri[0]), b = position(tri[1]), c = position(tri[2]);
            const Eigen::Vector3d n = (b - a).cross(c - a);
            areas[i] += n.norm() / 6.0;
            normals[i] += n;
        }
        if (normals[i].norm() > 0.0) normals[i] *= surface.outward_sign() / normals[i].norm();
    }
    out.contact = contact::penalty_contact(tool, parameters, inside_mm, areas, normals);
    std::unordered_map<std::uint32_t, std::size_t> node_index;
    for (contact::PointContact& c : out.contact.points) {
        const std::uint32_t v = inside[c.point];
        c.point = static_cast<std::uint32_t>(out.vertices.size());
        out.vertices.push_back(v);
        out.positions_mm.push_back(known.at(v));
        const std::uint32_t e = surface.vertex_element(v);
        out.elements.push_back(e);
        const Eigen::Matrix3d k = 1e3 * c.stiffness_n_per_mm * c.normal * c.normal.transpose(); // N/m
        for (int corner = 0; corner < 8; ++corner) {
            const double w = grid::hex8_shape(corner, surface.vertex_local(v));
            if (w == 0.0) continue;
            const std::uint32_t node = model.elements()[e].dof_node[corner];
            auto [it, added] = node_index.emplace(node, out.nodes.size());
            if (added) out.nodes.push_back({node, Eigen::Vector3d::Zero(), Eigen::Matrix3d::Zero()});
            out.nodes[it->second].force_n += w * c.force_n;
            out.nodes[it->second].stiffness_n_per_m += w * k;
        }
    }
    std::sort(out.elements.begin(), out.elements.end());
    out.elements.erase(std::unique(out.elements.begin(), out.elements.end()), out.elements.end());
    return out;
}

void merge_node_contacts(std::vector<fem::NodeContact>& a, const std::vector<fem::NodeContact>& b)
{
    std::unordered_map<std::uint32_t, std::size_t> index;
    for (std::size_t i = 0; i < a.size(); ++i) index.emplace(a[i].node, i);
    for (const fem::NodeContact& c : b) {
        const auto found = index.find(c.node);
        if (found == index.end()) {
            index.emplace(c.node, a.size());
            a.push_back(c);
        } else {
            a[found->second].force_n += c.force_n;
            a[found->second].stiffness_n_per_m += c.stiffness_n_per_m;
        }
    }
}

} // namespace vox::cut
