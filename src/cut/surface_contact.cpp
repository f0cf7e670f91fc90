#include "cut/surface_contact.hpp"

#include "grid/hex8.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <unordered_map>

namespace vox::cut {

namespace {

/// Surface vertex slots whose deformed position lies in `reach`, with those positions: vertices
/// of elements whose deformed corner box meets the reach, rest positions filtered first (a
/// vertex moves by its element's mean displacement give or take the corners' spread).
template <class Visit>
void vertices_in(const ModelSurface& surface, const std::vector<Eigen::Vector3d>& node_positions, const Eigen::AlignedBox3d& reach,
                 Visit&& visit)
{
    const fem::HexModel& model = surface.model();
    for (std::uint32_t e = 0; e < model.elements().size(); ++e) {
        const fem::HexElement& el = model.elements()[e];
        Eigen::AlignedBox3d box;
        box.setEmpty();
        for (std::uint32_t n : el.dof_node) box.extend(1e3 * node_positions[n]);
        if (!box.intersects(reach)) continue;
        Eigen::Vector3d mean = Eigen::Vector3d::Zero();
        for (std::uint32_t n : el.dof_node) mean += 1e3 * (node_positions[n] - model.rest_positions()[n]) / 8.0;
        double spread = 0.0;
        for (std::uint32_t n : el.dof_node) spread = std::max(spread, (1e3 * (node_positions[n] - model.rest_positions()[n]) - mean).norm());
        const Eigen::AlignedBox3d rest_reach(reach.min() - mean - Eigen::Vector3d::Constant(spread),
                                             reach.max() - mean + Eigen::Vector3d::Constant(spread));
        surface.for_each_element_vertex(e, [&](std::uint32_t v) {
            if (!rest_reach.contains(surface.vertex_rest_mm(v))) return;
            const Eigen::Vector3d p = surface.vertex_mm(v, node_positions);
            if (reach.contains(p)) visit(v, p);
        });
    }
}

/// Deformed vertex positions (world mm) computed once each: those already known are given up
/// front, the neighbours' looked up as the triangles around them ask.
class DeformedPositions {
public:
    DeformedPositions(const ModelSurface& surface, const std::vector<Eigen::Vector3d>& node_positions)
        : m_surface(surface), m_nodes(node_positions)
    {
    }
    /// Knowing already the positions `known_mm` of vertex slots `known`.
    DeformedPositions(const ModelSurface& surface, const std::vector<Eigen::Vector3d>& node_positions,
                      const std::vector<std::uint32_t>& known, const std::vector<Eigen::Vector3d>& known_mm)
        : DeformedPositions(surface, node_positions)
    {
        for (std::size_t i = 0; i < known.size(); ++i) add(known[i], known_mm[i]);
    }
    void add(std::uint32_t v, const Eigen::Vector3d& p) { m_known.emplace(v, p); }
    const Eigen::Vector3d& operator()(std::uint32_t v)
    {
        const auto found = m_known.find(v);
        if (found != m_known.end()) return found->second;
        return m_known.emplace(v, m_surface.vertex_mm(v, m_nodes)).first->second;
    }

private:
    const ModelSurface& m_surface;
    const std::vector<Eigen::Vector3d>& m_nodes;
    std::unordered_map<std::uint32_t, Eigen::Vector3d> m_known;
};

/// A third of the deformed area of the triangles around vertex slot `v`, and the area-weighted
/// mean of their outward normals; `position` gives deformed vertex positions.
void area_and_normal(const ModelSurface& surface, std::uint32_t v, DeformedPositions& position, double& area, Eigen::Vector3d& normal)
{
    area = 0.0;
    normal.setZero();
    const auto& triangles = surface.embedded().triangles();
    for (std::uint32_t t : surface.vertex_triangles(v)) {
        const auto& tri = triangles[t];
        const Eigen::Vector3d a = position(tri[0]), b = position(tri[1]), c = position(tri[2]);
        const Eigen::Vector3d n = (b - a).cross(c - a);
        area += n.norm() / 6.0;
        normal += n;
    }
    if (normal.norm() > 0.0) normal *= surface.outward_sign() / normal.norm();
}

/// The triangles whose three corners are among the points `point_of` numbers (vertex slot ->
/// point), in those numbers, each once (from its lowest-numbered corner).
std::vector<Eigen::Vector3i> triangles_among(const ModelSurface& surface, const std::unordered_map<std::uint32_t, int>& point_of)
{
    std::vector<Eigen::Vector3i> out;
    const auto& triangles = surface.embedded().triangles();
    for (const auto& [v, point] : point_of)
        for (std::uint32_t t : surface.vertex_triangles(v)) {
            Eigen::Vector3i corners;
            bool all = true;
            for (int c = 0; c < 3 && all; ++c) {
                const auto found = point_of.find(triangles[t][static_cast<std::size_t>(c)]);
                all = found != point_of.end();
                if (all) corners[c] = found->second;
            }
            if (all && corners.minCoeff() == point) out.push_back(corners);
        }
    return out;
}

/// Renumbers `out`'s contact points to the vertex slots `inside` they index, and gathers their
/// forces on the model's nodes.
void gather_on_nodes(const ModelSurface& surface, const std::vector<std::uint32_t>& inside, SurfaceContact& out)
{
    for (contact::PointContact& c : out.contact.points) {
        const std::uint32_t v = inside[c.point];
        c.point = static_cast<std::uint32_t>(out.vertices.size());
        out.vertices.push_back(v);
        out.keys.push_back(surface.embedded().vertices()[v].key);
        out.elements.push_back(surface.vertex_element(v));
    }
    out.nodes = node_contacts(surface, out);
    std::sort(out.elements.begin(), out.elements.end());
    out.elements.erase(std::unique(out.elements.begin(), out.elements.end()), out.elements.end());
}

} // namespace

VertexWeights vertex_weights(const Eigen::Vector3d& local)
{
    VertexWeights out;
    double total = 0.0;
    for (int c = 0; c < 8; ++c) total += std::abs(out.force[static_cast<std::size_t>(c)] = grid::hex8_shape(c, local));
    for (std::size_t c = 0; c < 8; ++c) out.stiffness[c] = std::abs(out.force[c]) * total;
    return out;
}


SurfaceContact touch_surface(const ModelSurface& surface, const std::vector<Eigen::Vector3d>& node_positions,
                             const contact::PlacedShape& tool, const contact::ContactParameters& parameters,
                             const contact::PlacedShape* from)
{
    SurfaceContact out;
    // Candidate points: the vertices near the tool, kept when inside the outer shape (at either
    // pose) or near enough for an edge of theirs to reach in (no edge is longer than two voxels).
    const double edge_reach = parameters.margin_mm + 2.0e3 * surface.grid().voxels().voxel_size_m().maxCoeff();
    Eigen::AlignedBox3d reach = tool.world_bounds(edge_reach);
    if (from) reach.extend(from->world_bounds(edge_reach));
    std::vector<std::uint32_t> near;
    std::vector<Eigen::Vector3d> near_mm;
    bool touching = false;
    // Something may touch only where a vertex is within the margin, or within half the longest
    // edge beyond it (an edge whose ends are both farther cannot reach in).
    const double may_touch = 0.5 * (parameters.margin_mm + edge_reach);
    vertices_in(surface, node_positions, reach, [&](std::uint32_t v, const Eigen::Vector3d& p) {
        const double d = std::min(tool.signed_distance(p), from ? from->signed_distance(p) : INFINITY);
        if (d >= edge_reach) return;
        touching = touching || d < may_touch;
        near.push_back(v);
        near_mm.push_back(p);
    });
    if (!touching) return out;
    DeformedPositions position(surface, node_positions, near, near_mm);
    std::vector<double> areas(near.size(), 0.0);
    std::vector<Eigen::Vector3d> normals(near.size(), Eigen::Vector3d::Zero());
    for (std::size_t i = 0; i < near.size(); ++i) area_and_normal(surface, near[i], position, areas[i], normals[i]);
    // The triangles among them, for the edges.
    std::unordered_map<std::uint32_t, int> index;
    for (std::size_t i = 0; i < near.size(); ++i) index.emplace(near[i], static_cast<int>(i));
    out.contact = contact::penalty_contact(tool, parameters, near_mm, areas, normals, from, triangles_among(surface, index));
    gather_on_nodes(surface, near, out);
    return out;
}

SurfaceContact touch_obstacle(const ModelSurface& surface, const std::vector<Eigen::Vector3d>& node_positions,
                              const std::vector<Eigen::Vector3d>& node_ends, const std::vector<Eigen::Vector3d>& node_velocities,
                              double dt_s, const contact::Obstacle& obstacle, contact::FrictionAnchors& anchors, double skin_mm)
{
    SurfaceContact out;
    const fem::HexModel& model = surface.model();
    std::vector<std::uint32_t> near;
    std::vector<Eigen::Vector3d> near_mm, ends_mm, velocities;
    for (std::uint32_t e = 0; e < model.elements().size(); ++e) {
        // The element's box swept over the step, so that a vertex arriving is caught.
        const fem::HexElement& el = model.elements()[e];
        Eigen::AlignedBox3d box;
        box.setEmpty();
        for (std::uint32_t n : el.dof_node) {
            box.extend(1e3 * node_positions[n]);
            box.extend(1e3 * node_ends[n]);
        }
        if (!obstacle.may_reach(Eigen::AlignedBox3d(box.min().array() - skin_mm, box.max().array() + skin_mm))) continue;
        surface.for_each_element_vertex(e, [&](std::uint32_t v) {
            const Eigen::Vector3d p = surface.vertex_mm(v, node_positions), end = surface.vertex_mm(v, node_ends);
            if (obstacle.signed_distance(p) >= skin_mm && obstacle.signed_distance(end) >= 0.0) return;
            Eigen::Vector3d velocity = Eigen::Vector3d::Zero();
            for (int corner = 0; corner < 8; ++corner)
                velocity += 1e3 * grid::hex8_shape(corner, surface.vertex_local(v)) * node_velocities[el.dof_node[corner]];
            near.push_back(v);
            near_mm.push_back(p);
            ends_mm.push_back(end);
            velocities.push_back(velocity);
        });
    }
    if (near.empty()) return out;
    DeformedPositions position(surface, node_positions, near, near_mm);
    std::vector<double> areas(near.size(), 0.0);
    std::vector<std::uint64_t> keys(near.size());
    Eigen::Vector3d normal;
    for (std::size_t i = 0; i < near.size(); ++i) {
        area_and_normal(surface, near[i], position, areas[i], normal);
        keys[i] = surface.embedded().vertices()[near[i]].key;
    }
    out.contact = contact::obstacle_contact(obstacle, near_mm, areas, velocities, dt_s, keys, anchors, skin_mm, ends_mm);
    gather_on_nodes(surface, near, out);
    // The push along the normal is taken at the step's end and let go if it would pull there: a
    // pair contact with one side (the obstacle does not move). Friction stays on the nodes.
    out.nodes.clear();
    std::unordered_map<std::uint32_t, std::size_t> node_index;
    for (const contact::PointContact& c : out.contact.points) {
        const std::uint32_t v = out.vertices[c.point];
        fem::PairContact pair;
        add_vertex_terms(surface, v, 1.0, pair.terms);
        pair.normal = c.normal;
        pair.force_n = c.normal_force_n();
        pair.stiffness_n_per_m = 1e3 * c.stiffness_n_per_mm;
        pair.waiting = c.depth_mm <= -skin_mm;
        out.pairs.push_back(std::move(pair));
        if (c.friction_stiffness_n_per_mm.isZero()) continue;
        const fem::HexElement& el = model.elements()[surface.vertex_element(v)];
        const VertexWeights w = vertex_weights(surface.vertex_local(v));
        for (std::size_t corner = 0; corner < 8; ++corner) {
            if (w.force[corner] == 0.0) continue;
            const std::uint32_t node = el.dof_node[corner];
            auto [it, added] = node_index.emplace(node, out.nodes.size());
            if (added) out.nodes.push_back({node, Eigen::Vector3d::Zero(), Eigen::Matrix3d::Zero()});
            out.nodes[it->second].force_n += w.force[corner] * c.across_force_n();
            out.nodes[it->second].stiffness_n_per_m += w.stiffness[corner] * 1e3 * c.friction_stiffness_n_per_mm;
        }
    }
    return out;
}

void add_vertex_terms(const ModelSurface& surface, std::uint32_t v, double weight, std::vector<fem::BlockWeight>& terms)
{
    const fem::HexElement& el = surface.model().elements()[surface.vertex_element(v)];
    const Eigen::Vector3d local = surface.vertex_local(v);
    for (int corner = 0; corner < 8; ++corner) {
        const double w = weight * grid::hex8_shape(corner, local);
        if (w == 0.0) continue;
        fem::add_term(terms, el.dof_node[static_cast<std::size_t>(corner)], w);
    }
}

std::vector<fem::NodeContact> node_contacts(const ModelSurface& surface, const SurfaceContact& contact)
{
    const fem::HexModel& model = surface.model();
    const auto& vertices = surface.embedded().vertices();
    std::vector<fem::NodeContact> out;
    std::unordered_map<std::uint32_t, std::size_t> node_index;
    for (const contact::PointContact& c : contact.contact.points) {
        const std::uint32_t v = contact.vertices[c.point];
        if (v >= vertices.size() || vertices[v].users == 0 || vertices[v].key != contact.keys[c.point]) continue;
        const std::uint32_t e = surface.vertex_element(v);
        const Eigen::Matrix3d k = 1e3 * c.stiffness_matrix_n_per_mm(); // N/m
        const VertexWeights w = vertex_weights(surface.vertex_local(v));
        for (std::size_t corner = 0; corner < 8; ++corner) {
            if (w.force[corner] == 0.0) continue;
            const std::uint32_t node = model.elements()[e].dof_node[corner];
            auto [it, added] = node_index.emplace(node, out.size());
            if (added) out.push_back({node, Eigen::Vector3d::Zero(), Eigen::Matrix3d::Zero()});
            out[it->second].force_n += w.force[corner] * c.force_n;
            out[it->second].stiffness_n_per_m += w.stiffness[corner] * k;
        }
    }
    return out;
}

void sample_surface(const ModelSurface& surface, const std::vector<Eigen::Vector3d>& node_positions, const Eigen::AlignedBox3d& box,
                    contact::SurfacePoints& out, const std::vector<double>* node_stiffness)
{
    out.count = 0;
    out.truncated = false;
    out.stiffness_n_per_mm.clear();
    std::vector<std::uint32_t> slots;
    DeformedPositions position(surface, node_positions);
    vertices_in(surface, node_positions, box, [&](std::uint32_t v, const Eigen::Vector3d& p) {
        slots.push_back(v);
        position.add(v, p);
    });
    std::unordered_map<std::uint32_t, int> point_of; // vertex slot -> point index
    for (std::uint32_t v : slots) {
        if (out.count == out.capacity()) {
            out.truncated = true;
            break;
        }
        point_of.emplace(v, static_cast<int>(out.count));
        out.positions_mm[out.count] = position(v);
        area_and_normal(surface, v, position, out.areas_mm2[out.count], out.normals[out.count]);
        if (node_stiffness) {
            const fem::HexElement& el = surface.model().elements()[surface.vertex_element(v)];
            const Eigen::Vector3d local = surface.vertex_local(v);
            double k = 0.0;
            for (int c = 0; c < 8; ++c) k += grid::hex8_shape(c, local) * (*node_stiffness)[el.dof_node[c]];
            out.stiffness_n_per_mm.push_back(k);
        }
        ++out.count;
    }
    // The triangles among the points, their tree and edges.
    out.triangles = triangles_among(surface, point_of);
    out.index();
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
