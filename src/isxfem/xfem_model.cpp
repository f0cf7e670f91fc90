#include "isxfem/xfem_model.hpp"

#include "core/union_find.hpp"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <stdexcept>
#include <string>
#include <unordered_set>

namespace vox::isxfem {
namespace {

/// The smallest region (share of its tetrahedron) a second cut may leave between itself and the first.
constexpr double k_min_second_cut_region = 0.01;

/// Whether two cuts that do not cross in a tetrahedron (three regions) leave a region between them
/// (the one across each cut from another) under k_min_second_cut_region of its `volume`.
bool sliver_between(const std::vector<Region>& regions, double volume)
{
    if (regions.size() != 3) return false;
    unsigned missing = 0;
    for (unsigned p = 0; p < 4; ++p)
        if (std::none_of(regions.begin(), regions.end(), [p](const Region& r) { return r.pattern == p; })) missing = p;
    const unsigned middle = missing ^ 3u;
    return std::any_of(regions.begin(), regions.end(),
                       [&](const Region& r) { return r.pattern == middle && r.volume < k_min_second_cut_region * volume; });
}

} // namespace

XfemModel::XfemModel(TetMesh mesh, std::vector<grid::ElasticMaterial> materials, std::vector<std::uint32_t> material, double k)
    : m_mesh(std::move(mesh)), m_materials(std::move(materials)), m_k(k)
{
    if (!(k >= 0.0 && k <= 1.0)) throw std::invalid_argument("XfemModel: k must be in [0, 1], got " + std::to_string(k));
    if (material.size() != m_mesh.tets.size()) throw std::invalid_argument("XfemModel: one material per tetrahedron");
    m_elements.resize(m_mesh.tets.size());
    m_support.assign(m_mesh.nodes.size(), 0.0);
    for (std::size_t t = 0; t < m_mesh.tets.size(); ++t) {
        XfemElement& e = m_elements[t];
        e.node = m_mesh.tets[t];
        if (material[t] >= m_materials.size()) throw std::invalid_argument("XfemModel: material index out of range");
        e.material = material[t];
        e.geometry = tet_geometry(m_mesh.corners(t));
        const grid::ElasticMaterial& m = m_materials[e.material];
        e.stiffness = tet_stiffness(e.geometry, m.lame);
        e.mass = tet_mass(e.geometry, m.density_kg_m3);
        for (std::uint32_t n : e.node) m_support[n] += e.geometry.volume;
        for (std::size_t a = 0; a < 4; ++a)
            for (std::size_t b = a + 1; b < 4; ++b)
                m_longest_edge = std::max(m_longest_edge, (m_mesh.nodes[e.node[a]] - m_mesh.nodes[e.node[b]]).norm());
    }
}

CutReport XfemModel::cut(const PlaneCut& plane, const std::function<bool(const Eigen::Vector3d&)>& inside, int extend)
{
    if (extend >= m_cuts) throw std::invalid_argument("XfemModel::cut: no cut " + std::to_string(extend) + " to extend");
    const CutSurface surface = extend >= 0 ? m_surfaces[static_cast<std::size_t>(extend)] : CutSurface(plane);
    return cut_along(
        extend >= 0 ? extend : m_cuts, extend >= 0, surface, [](std::size_t) { return true; },
        [&inside](const Eigen::Vector3d&, const Eigen::Vector3d&, const Eigen::Vector3d& crossing) { return !inside || inside(crossing); });
}

CutReport XfemModel::cut(const CutSurface& surface, std::size_t new_from, int extend)
{
    if (extend >= m_cuts) throw std::invalid_argument("XfemModel::cut: no cut " + std::to_string(extend) + " to extend");
    if (extend >= 0) m_surfaces[static_cast<std::size_t>(extend)] = surface;
    // A new patch can also become the nearest for a node a little beyond its box.
    Eigen::AlignedBox3d reach = surface.bounds(new_from);
    reach.extend(reach.min() - Eigen::Vector3d::Constant(m_longest_edge));
    reach.extend(reach.max() + Eigen::Vector3d::Constant(m_longest_edge));
    auto candidate = [&](std::size_t t) {
        Eigen::AlignedBox3d box;
        box.setEmpty();
        for (std::uint32_t n : m_elements[t].node) box.extend(m_mesh.nodes[n]);
        return box.intersects(reach);
    };
    // An edge is cut where a patch meets it (Möller's test), or where its level crosses over a
    // patch, close to its plane: an edge with an end almost on the surface (a blade drawn along a
    // node plane) may pass just beside every patch, its nodes' levels taken from the nearest one.
    const double off = 0.25 * m_longest_edge;
    return cut_along(extend >= 0 ? extend : m_cuts, extend >= 0, surface, candidate,
                     [&surface, off](const Eigen::Vector3d& a, const Eigen::Vector3d& b, const Eigen::Vector3d& crossing) {
                         return surface.meets(a, b) || surface.covers(crossing, off);
                     });
}

double XfemModel::node_level(int id, std::uint32_t node) const
{
    const auto& fixed = m_node_levels.at(static_cast<std::size_t>(id));
    const auto it = fixed.find(node);
    return it != fixed.end() ? it->second : m_surfaces[static_cast<std::size_t>(id)].level(m_mesh.nodes[node]);
}

double XfemModel::level(int id, std::size_t tet, const std::array<double, 4>& bary) const
{
    double phi = 0.0;
    for (std::size_t c = 0; c < 4; ++c) phi += bary[c] * node_level(id, m_elements[tet].node[c]);
    return phi;
}

Eigen::Vector3d XfemModel::crack_normal(int id, std::size_t tet) const
{
    const XfemElement& e = m_elements[tet];
    Eigen::Vector4d phi;
    for (std::size_t c = 0; c < 4; ++c) phi[static_cast<Eigen::Index>(c)] = node_level(id, e.node[c]);
    const Eigen::Vector3d gradient = e.geometry.gradient.transpose() * phi;
    if (gradient.squaredNorm() > 0.0) return gradient.normalized();
    Eigen::Vector3d middle = Eigen::Vector3d::Zero();
    for (std::uint32_t n : e.node) middle += 0.25 * m_mesh.nodes[n];
    return m_surfaces[static_cast<std::size_t>(id)].normal(middle);
}

void XfemModel::leave_out_islands(int id, std::vector<std::uint32_t>& candidates, std::vector<std::array<double, 4>>& phi,
                                  CutReport& report) const
{
    // Where a swept surface ends inside the material (a blade's edge, a shallow stroke), it can
    // cross a few tetrahedra whole with tetrahedra it crosses only partly between them: islands
    // of one crack that touch at nodes, each a slit of its own (a two-phase stroke marked a
    // millimetre deep made two). A crack is one surface: of pieces of it that lie within a
    // tetrahedron of each other but join across no edge it crosses, the piece the crack already
    // had (or the largest) is cut, the others wait until the tetrahedra between them are crossed
    // whole too. Pieces farther apart (a stroke through both arms of a U) are all cut.
    std::vector<std::uint32_t> tets;
    std::vector<std::array<bool, 4>> side;
    for (std::uint32_t t = 0; t < m_elements.size(); ++t)
        if (const int k = m_elements[t].cut_index(id); k >= 0) {
            tets.push_back(t);
            const auto& ns = m_elements[t].cuts[static_cast<std::size_t>(k)].node_side;
            side.push_back({ns[0] != 0, ns[1] != 0, ns[2] != 0, ns[3] != 0});
        }
    const std::size_t existing = tets.size();
    for (std::size_t i = 0; i < candidates.size(); ++i) {
        tets.push_back(candidates[i]);
        side.push_back({phi[i][0] < 0.0, phi[i][1] < 0.0, phi[i][2] < 0.0, phi[i][3] < 0.0});
    }
    if (candidates.empty()) return;
    // Pieces: tetrahedra joined across the edges the crack crosses.
    UnionFind piece(tets.size());
    std::unordered_map<std::uint64_t, std::uint32_t> edge_owner;
    std::unordered_map<std::uint32_t, std::uint32_t> node_owner;
    for (std::uint32_t k = 0; k < tets.size(); ++k) {
        const auto& node = m_elements[tets[k]].node;
        for (std::size_t a = 0; a < 4; ++a)
            for (std::size_t b = a + 1; b < 4; ++b)
                if (side[k][a] != side[k][b]) {
                    const std::uint64_t edge = std::uint64_t{std::min(node[a], node[b])} << 32 | std::max(node[a], node[b]);
                    if (const auto [it, fresh] = edge_owner.try_emplace(edge, k); !fresh) piece.unite(it->second, k);
                }
    }
    // Groups: pieces that touch at a node, or at two nodes of one tetrahedron (a tetrahedron the
    // surface crosses partly between them).
    UnionFind group(tets.size());
    for (std::uint32_t k = 0; k < tets.size(); ++k)
        for (std::uint32_t n : m_elements[tets[k]].node)
            if (const auto [it, fresh] = node_owner.try_emplace(n, k); !fresh) group.unite(piece.find(it->second), piece.find(k));
    for (const XfemElement& e : m_elements) {
        std::uint32_t first = ~0u;
        for (std::uint32_t n : e.node)
            if (const auto it = node_owner.find(n); it != node_owner.end()) {
                if (first == ~0u) first = it->second;
                else group.unite(piece.find(first), piece.find(it->second));
            }
    }
    // In each group, the pieces the crack had, or else its largest piece.
    std::unordered_map<std::uint32_t, std::uint32_t> size;
    std::unordered_set<std::uint32_t> had, group_had; // pieces, groups holding tetrahedra cut before
    for (std::uint32_t k = 0; k < tets.size(); ++k) {
        const std::uint32_t p = piece.find(k);
        ++size[p];
        if (k < existing) {
            had.insert(p);
            group_had.insert(group.find(p));
        }
    }
    std::unordered_map<std::uint32_t, std::uint32_t> largest; // per group
    for (const auto& [p, n] : size) {
        const auto [it, fresh] = largest.try_emplace(group.find(p), p);
        if (!fresh && (n > size[it->second] || (n == size[it->second] && p < it->second))) it->second = p;
    }
    std::size_t kept = 0;
    for (std::size_t i = 0; i < candidates.size(); ++i) {
        const std::uint32_t p = piece.find(static_cast<std::uint32_t>(existing + i)), g = group.find(p);
        if (group_had.contains(g) ? had.contains(p) : largest[g] == p) {
            candidates[kept] = candidates[i];
            phi[kept++] = phi[i];
        } else {
            ++report.partial_tets;
        }
    }
    candidates.resize(kept);
    phi.resize(kept);
}

CutReport XfemModel::cut_along(int id, bool extend, const CutSurface& surface, const std::function<bool(std::size_t)>& candidate,
                               const EdgeTest& covered)
{
    CutReport report;
    std::unordered_map<std::uint32_t, std::uint32_t> fresh_blocks;
    std::unordered_map<std::uint32_t, double> fresh_levels;
    auto& block_of_node = extend ? m_cut_blocks[static_cast<std::size_t>(id)] : fresh_blocks;
    auto& level_of_node = extend ? m_node_levels[static_cast<std::size_t>(id)] : fresh_levels;
    // Which tetrahedra the cut separates whole, then their cut matrices on all threads (the
    // quadrature is most of a cut's time), then their enriched blocks in order.
    std::vector<std::uint32_t> candidates;
    std::vector<std::array<double, 4>> candidate_phi;
    std::unordered_map<std::uint32_t, double> evaluated; // the surface's level at nodes not fixed, once each
    auto node_phi = [&](std::uint32_t n) {
        if (const auto fixed = level_of_node.find(n); fixed != level_of_node.end()) return fixed->second;
        const auto [it, fresh] = evaluated.try_emplace(n, 0.0);
        if (fresh) it->second = surface.level(m_mesh.nodes[n]);
        return it->second;
    };
    for (std::size_t t = 0; t < m_elements.size(); ++t) {
        XfemElement& e = m_elements[t];
        if (e.cut_index(id) >= 0 || !candidate(t)) continue;
        std::array<double, 4> phi{};
        bool negative = false, positive = false;
        for (std::size_t c = 0; c < 4; ++c) {
            phi[c] = node_phi(e.node[c]);
            (phi[c] < 0.0 ? negative : positive) = true;
        }
        if (!negative || !positive) continue;
        // A closed boundary: every edge the level crosses is cut.
        bool whole = true;
        for (std::size_t a = 0; a < 4 && whole; ++a)
            for (std::size_t b = a + 1; b < 4 && whole; ++b)
                if ((phi[a] < 0.0) != (phi[b] < 0.0)) {
                    const Eigen::Vector3d& xa = m_mesh.nodes[e.node[a]];
                    const Eigen::Vector3d& xb = m_mesh.nodes[e.node[b]];
                    whole = covered(xa, xb, xa + phi[a] / (phi[a] - phi[b]) * (xb - xa));
                }
        if (!whole) {
            ++report.partial_tets;
            continue;
        }
        if (e.cuts.size() >= k_max_cuts) {
            ++report.already_cut; // cut as often as it can be: left as it was, and marked
            e.cut_left_out = true;
            continue;
        }
        candidates.push_back(static_cast<std::uint32_t>(t));
        candidate_phi.push_back(phi);
    }
    leave_out_islands(id, candidates, candidate_phi, report);
    // A first cut by moment fitting (cut_tet); a second by the regions both cuts leave.
    std::vector<MultiCutTet> matrices(candidates.size());
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, candidates.size(), 4), [&](const tbb::blocked_range<std::size_t>& range) {
        for (std::size_t i = range.begin(); i < range.end(); ++i) {
            const XfemElement& e = m_elements[candidates[i]];
            const grid::ElasticMaterial& m = m_materials[e.material];
            const auto corners = m_mesh.corners(candidates[i]);
            if (e.cuts.empty()) {
                const CutTet c = cut_tet(corners, candidate_phi[i], m_k, m.lame, m.density_kg_m3, m_fitting);
                for (unsigned side = 0; side < 2; ++side)
                    if (c.side_volume[side] > 0.0) matrices[i].regions.push_back({side, c.side_volume[side], c.side_stiffness[side]});
                matrices[i].mass = c.mass;
                matrices[i].node_side = {c.node_side};
            } else {
                std::vector<std::array<double, 4>> phi;
                for (const ElementCut& earlier : e.cuts) phi.push_back(earlier.phi);
                phi.push_back(candidate_phi[i]);
                matrices[i] = multi_cut_tet(corners, phi, m_k, m.lame, m.density_kg_m3);
            }
        }
    });
    for (std::size_t i = 0; i < candidates.size(); ++i) {
        XfemElement& e = m_elements[candidates[i]];
        MultiCutTet& c = matrices[i];
        // The new cut's sides within the element: both must hold material.
        const std::size_t bit = e.cuts.size();
        std::array<double, 2> side_volume{};
        for (const Region& r : c.regions) side_volume[(r.pattern >> bit) & 1u] += r.volume;
        if (std::min(side_volume[0], side_volume[1]) <= 0.0) {
            ++report.partial_tets; // the plane only touches it (through nodes): nothing to separate
            continue;
        }
        // A second cut running alongside the first within the tetrahedron (a blade drawn again
        // along a crack) would leave a sliver between them, whose pieces' rotations and dofs the
        // solve cannot hold (a haptic session cutting the same plane over and over diverged): the
        // earlier crack is taken to separate it. (A small corner either cut leaves is kept.)
        if (!e.cuts.empty() && sliver_between(c.regions, e.geometry.volume)) {
            if (!e.left_to_earlier_cut) ++report.beside_earlier; // each tetrahedron once, though asked again each frame
            e.left_to_earlier_cut = true;
            continue;
        }
        if (!e.cuts.empty()) {
            ++report.recut_tets;
            e.crossed = c.regions.size() == (1u << (bit + 1));
            report.crossed_tets += e.crossed ? 1 : 0;
        }
        ElementCut cut;
        cut.id = id;
        cut.phi = candidate_phi[i];
        for (std::size_t n = 0; n < 4; ++n) level_of_node.try_emplace(e.node[n], cut.phi[n]);
        cut.node_side = c.node_side.back();
        for (std::size_t n = 0; n < 4; ++n) {
            const auto [it, added] = block_of_node.try_emplace(e.node[n], static_cast<std::uint32_t>(block_count()));
            if (added) {
                m_enriched_node.push_back(e.node[n]);
                m_enriched_across.push_back(0.0);
                ++report.new_blocks;
            }
            cut.enriched[n] = it->second;
            m_enriched_across[it->second - node_count()] += side_volume[1u - cut.node_side[n]];
        }
        e.cuts.push_back(cut);
        e.regions = std::move(c.regions);
        e.mass = std::move(c.mass);
        ++report.cut_tets;
    }
    if (report.cut_tets > 0) {
        ++m_revision;
        report.cut = id;
        if (!extend) {
            m_cut_blocks.push_back(std::move(fresh_blocks));
            m_node_levels.push_back(std::move(fresh_levels));
            m_surfaces.push_back(surface);
            ++m_cuts;
        }
    }
    return report;
}

} // namespace vox::isxfem
