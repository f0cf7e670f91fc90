#include "isxfem/xfem_model.hpp"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <stdexcept>
#include <string>

namespace vox::isxfem {

XfemModel::XfemModel(TetMesh mesh, std::vector<TetMaterial> materials, std::vector<std::uint32_t> material, double k)
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
        const TetMaterial& m = m_materials[e.material];
        e.stiffness = tet_stiffness(e.geometry, m.lame);
        e.mass.topLeftCorner<12, 12>() = tet_mass(e.geometry, m.density);
        for (std::uint32_t n : e.node) m_support[n] += e.geometry.volume;
    }
}

CutReport XfemModel::cut(const PlaneCut& plane, const std::function<bool(const Eigen::Vector3d&)>& inside, int extend)
{
    if (extend >= m_cuts) throw std::invalid_argument("XfemModel::cut: no cut " + std::to_string(extend) + " to extend");
    CutReport report;
    const int id = extend >= 0 ? extend : m_cuts;
    std::unordered_map<std::uint32_t, std::uint32_t> fresh;
    std::unordered_map<std::uint32_t, std::uint32_t>& block_of_node = extend >= 0 ? m_cut_blocks[static_cast<std::size_t>(extend)] : fresh;
    // Which tetrahedra the cut separates whole, then their cut matrices on all threads (the
    // moment-fitted quadrature is most of a cut's time), then their enriched blocks in order.
    std::vector<std::uint32_t> candidates;
    std::vector<std::array<double, 4>> candidate_phi;
    for (std::size_t t = 0; t < m_elements.size(); ++t) {
        const XfemElement& e = m_elements[t];
        std::array<double, 4> phi{};
        bool negative = false, positive = false;
        for (std::size_t c = 0; c < 4; ++c) {
            phi[c] = plane.at(m_mesh.nodes[e.node[c]]);
            (phi[c] < 0.0 ? negative : positive) = true;
        }
        if (!negative || !positive) continue;
        if (e.cut >= 0) {
            if (e.cut != id) ++report.already_cut; // another cut's: left as it was (one cut per tetrahedron)
            continue;
        }
        // A closed boundary: every edge the plane crosses is crossed inside the region.
        bool whole = true;
        for (std::size_t a = 0; a < 4 && whole && inside; ++a)
            for (std::size_t b = a + 1; b < 4 && whole; ++b)
                if ((phi[a] < 0.0) != (phi[b] < 0.0)) {
                    const double f = phi[a] / (phi[a] - phi[b]);
                    whole = inside(m_mesh.nodes[e.node[a]] + f * (m_mesh.nodes[e.node[b]] - m_mesh.nodes[e.node[a]]));
                }
        if (!whole) {
            ++report.partial_tets;
            continue;
        }
        candidates.push_back(static_cast<std::uint32_t>(t));
        candidate_phi.push_back(phi);
    }
    std::vector<CutTet> matrices(candidates.size());
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, candidates.size(), 4), [&](const tbb::blocked_range<std::size_t>& range) {
        for (std::size_t i = range.begin(); i < range.end(); ++i) {
            const XfemElement& e = m_elements[candidates[i]];
            const TetMaterial& m = m_materials[e.material];
            matrices[i] = cut_tet(m_mesh.corners(candidates[i]), candidate_phi[i], m_k, m.lame, m.density, m_fitting);
        }
    });
    for (std::size_t i = 0; i < candidates.size(); ++i) {
        XfemElement& e = m_elements[candidates[i]];
        const CutTet& c = matrices[i];
        if (std::min(c.side_volume[0], c.side_volume[1]) <= 0.0) {
            ++report.partial_tets; // the plane only touches it (through nodes): nothing to separate
            continue;
        }
        e.cut = id;
        e.phi = candidate_phi[i];
        e.node_side = c.node_side;
        e.side_volume = c.side_volume;
        e.side_stiffness = c.side_stiffness;
        e.mass = c.mass;
        for (std::size_t n = 0; n < 4; ++n) {
            const auto [it, added] = block_of_node.try_emplace(e.node[n], static_cast<std::uint32_t>(block_count()));
            if (added) {
                m_enriched_node.push_back(e.node[n]);
                m_enriched_across.push_back(0.0);
                ++report.new_blocks;
            }
            e.enriched[n] = it->second;
            m_enriched_across[it->second - node_count()] += c.side_volume[1u - c.node_side[n]];
        }
        ++report.cut_tets;
    }
    if (report.cut_tets > 0) {
        ++m_revision;
        report.cut = id;
        if (extend < 0) {
            m_cut_blocks.push_back(std::move(fresh));
            m_cut_planes.push_back(plane);
            ++m_cuts;
        }
    }
    return report;
}

} // namespace vox::isxfem
