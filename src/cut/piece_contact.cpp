#include "cut/piece_contact.hpp"

#include "cut/surface_contact.hpp"

#include "contact/box_grid.hpp"

#include "grid/hex8.hpp"

#include <Eigen/Geometry>

#include <algorithm>
#include <cmath>

namespace vox::cut {

namespace {

/// Elements holding surface vertices whose swept, deformed boxes come within `gap_mm` of another
/// such element's without sharing a node with it (the broad phase of the header), and those
/// pairs (indices into the list returned).
std::vector<std::uint32_t> elements_near_others(const ModelSurface& surface, const std::vector<Eigen::Vector3d>& start_m,
                                                const std::vector<Eigen::Vector3d>& end_m, double gap_mm,
                                                std::vector<std::pair<std::uint32_t, std::uint32_t>>& pairs)
{
    const fem::HexModel& model = surface.model();
    const auto& elements = model.elements();
    std::vector<std::uint32_t> candidates;
    std::vector<Eigen::AlignedBox3d> boxes;
    for (std::uint32_t e = 0; e < elements.size(); ++e) {
        if (!surface.element_has_vertex(e)) continue;
        Eigen::AlignedBox3d box;
        box.setEmpty();
        for (std::uint32_t n : elements[e].dof_node) {
            box.extend(1e3 * start_m[n]);
            box.extend(1e3 * end_m[n]);
        }
        candidates.push_back(e);
        boxes.emplace_back(box.min().array() - 0.5 * gap_mm, box.max().array() + 0.5 * gap_mm);
    }
    // Whether two elements share a node: eight lanes compared at once per node of the other.
    using Nodes = std::uint32_t __attribute__((vector_size(32)));
    auto joined = [&](std::uint32_t p, std::uint32_t q) {
        Nodes nq;
        __builtin_memcpy(&nq, elements[candidates[q]].dof_node.data(), sizeof nq);
        Nodes same{};
        for (std::uint32_t n : elements[candidates[p]].dof_node) same |= nq == n;
        for (int k = 0; k < 8; ++k)
            if (same[k]) return true;
        return false;
    };
    // A grid of cells the elements' edge wide: each box meets a few.
    const double cell = 1e3 * surface.grid().voxels().voxel_size_m().maxCoeff() * std::ldexp(1.0, model.level());
    std::vector<unsigned char> kept(candidates.size(), 0);
    std::vector<std::pair<std::uint32_t, std::uint32_t>> found;
    contact::BoxGrid(std::move(boxes), cell).overlapping_pairs([&](std::uint32_t p, std::uint32_t q) {
        if (!joined(p, q)) found.emplace_back(p, q);
    });
    for (const auto& [p, q] : found) kept[p] = kept[q] = 1;
    std::vector<std::uint32_t> out, place(candidates.size(), 0);
    for (std::uint32_t i = 0; i < candidates.size(); ++i)
        if (kept[i]) {
            place[i] = static_cast<std::uint32_t>(out.size());
            out.push_back(candidates[i]);
        }
    pairs.clear();
    for (const auto& [p, q] : found) pairs.emplace_back(place[p], place[q]);
    return out;
}

} // namespace

PieceContact touch_pieces(const ModelSurface& surface, const std::vector<Eigen::Vector3d>& node_positions,
                          const std::vector<Eigen::Vector3d>& node_ends, const contact::PieceContactParameters& parameters)
{
    PieceContact out;
    const std::vector<Eigen::Vector3d>& end = node_ends;
    std::vector<std::pair<std::uint32_t, std::uint32_t>> near_pairs;
    const std::vector<std::uint32_t> near = elements_near_others(surface, node_positions, end, parameters.approach_mm, near_pairs);
    out.element_pairs = near_pairs.size();
    if (near.empty()) return out;
    // The patch: the near elements' vertices and the corners of their triangles, each once.
    // By vertex slot, its place in the patch (none: ~0u); an array, not a hash map: the patch
    // takes tens of thousands of lookups a frame.
    constexpr std::uint32_t none = ~0u;
    std::vector<std::uint32_t> index(surface.embedded().vertices().size(), none);
    const auto& triangles = surface.embedded().triangles();
    contact::SurfacePatch& patch = out.patch;
    auto add = [&](std::uint32_t v, bool presses) {
        if (index[v] == none) {
            index[v] = static_cast<std::uint32_t>(out.slots.size());
            out.slots.push_back(v);
            patch.presses.push_back(0);
        }
        if (presses) patch.presses[index[v]] = 1;
    };
    // Each near element's own vertices, swept over the step: a vertex presses only where it comes
    // within the gap of the surface of an element it is near (the elements' boxes are those of
    // coarse cells, and two parts of one cell have the same box: most of their vertices lie far
    // from the other part's surface, and cost the narrow phase nothing).
    struct Own {
        std::uint32_t vertex;
        Eigen::AlignedBox3d swept; ///< from its start to its end, mm
    };
    std::vector<std::vector<Own>> own(near.size());
    std::vector<Eigen::AlignedBox3d> swept(near.size());
    for (std::size_t i = 0; i < near.size(); ++i) {
        swept[i].setEmpty();
        surface.for_each_element_vertex(near[i], [&](std::uint32_t v) {
            Eigen::AlignedBox3d box(surface.vertex_mm(v, node_positions));
            box.extend(surface.vertex_mm(v, end));
            own[i].push_back({v, box});
            swept[i].extend(box);
        });
    }
    std::vector<std::vector<std::uint32_t>> partners(near.size());
    for (const auto& [p, q] : near_pairs) {
        partners[p].push_back(q);
        partners[q].push_back(p);
    }
    // The gap, plus room for the triangles a vertex presses (a voxel's diagonal) and how deep it
    // may be (max_depth): a triangle comes in when any of its corners does.
    const double gap = parameters.approach_mm + 2.0 * parameters.max_depth_mm;
    for (std::size_t i = 0; i < near.size(); ++i)
        for (const auto& [v, moved] : own[i]) {
            Eigen::AlignedBox3d box = moved;
            box.min().array() -= gap;
            box.max().array() += gap;
            const bool reaches = std::any_of(partners[i].begin(), partners[i].end(), [&](std::uint32_t j) { return swept[j].intersects(box); });
            if (!reaches) continue;
            add(v, true);
            for (std::uint32_t t : surface.vertex_triangles(v))
                for (std::uint32_t c : triangles[t]) add(c, false);
        }
    patch.outward_sign = surface.outward_sign();
    for (std::uint32_t v : out.slots) {
        patch.start_mm.push_back(surface.vertex_mm(v, node_positions));
        patch.end_mm.push_back(surface.vertex_mm(v, end));
        patch.rest_mm.push_back(surface.vertex_rest_mm(v));
    }
    // Triangles among the patch's vertices, each once; the near elements' own vertices press.
    for (std::uint32_t i = 0; i < out.slots.size(); ++i)
        for (std::uint32_t t : surface.vertex_triangles(out.slots[i])) {
            Eigen::Vector3i corners;
            bool all = true;
            for (int c = 0; c < 3 && all; ++c) {
                const std::uint32_t at = index[triangles[t][static_cast<std::size_t>(c)]];
                all = at != none;
                if (all) corners[c] = static_cast<int>(at);
            }
            if (all && static_cast<std::uint32_t>(corners.minCoeff()) == i) patch.triangles.push_back(corners);
        }
    contact::SurfaceContacts found = contact::surface_contacts(patch, parameters);
    out.faces = std::move(found.faces);
    out.edges = std::move(found.edges);
    // On the nodes: the pressing point's weights on its vertices times their elements', minus the
    // pressed point's.
    auto on_nodes = [&](std::uint32_t i, double w, std::vector<fem::BlockWeight>& terms) { add_vertex_terms(surface, out.slots[i], w, terms); };
    for (const contact::FaceContact& f : out.faces) out.pairs.push_back(face_pair(f, patch, parameters.skin_mm, on_nodes));
    for (const contact::EdgeContact& e : out.edges) out.pairs.push_back(edge_pair(e, parameters.skin_mm, on_nodes));
    return out;
}

} // namespace vox::cut
