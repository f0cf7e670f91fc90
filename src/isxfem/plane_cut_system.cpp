#include "isxfem/plane_cut_system.hpp"

#include "isxfem/xfem_tetrahedron.hpp"

namespace vox::isxfem {

PlaneCutSystem assemble_plane_cut(const TetMesh& mesh, const PlaneCut& cut, double k, const grid::Lame& lame, double density)
{
    const MomentFitting fitting;
    const std::size_t n = mesh.nodes.size();
    PlaneCutSystem out;
    out.enriched.assign(n, -1);
    auto phi_of = [&](std::size_t t) {
        std::array<double, 4> phi{};
        for (int c = 0; c < 4; ++c) phi[static_cast<std::size_t>(c)] = cut.at(mesh.nodes[mesh.tets[t][static_cast<std::size_t>(c)]]);
        return phi;
    };
    auto is_cut = [](const std::array<double, 4>& phi) {
        bool negative = false, positive = false;
        for (double p : phi) (p < 0.0 ? negative : positive) = true;
        return negative && positive;
    };
    std::int32_t enriched_count = 0;
    for (std::size_t t = 0; t < mesh.tets.size(); ++t)
        if (is_cut(phi_of(t)))
            for (std::uint32_t node : mesh.tets[t])
                if (out.enriched[node] < 0) out.enriched[node] = enriched_count++;
    const std::size_t dofs = 3 * (n + static_cast<std::size_t>(enriched_count));
    std::vector<double> support(n, 0.0), across(n, 0.0);
    std::vector<Eigen::Triplet<double>> k_entries, m_entries;
    auto add = [&](const auto& ke, const auto& me, const std::vector<std::size_t>& dof_of_block) {
        for (std::size_t a = 0; a < dof_of_block.size(); ++a)
            for (std::size_t b = 0; b < dof_of_block.size(); ++b)
                for (int i = 0; i < 3; ++i)
                    for (int j = 0; j < 3; ++j) {
                        const auto r = static_cast<int>(dof_of_block[a] + static_cast<std::size_t>(i));
                        const auto c = static_cast<int>(dof_of_block[b] + static_cast<std::size_t>(j));
                        const double kv = ke(static_cast<Eigen::Index>(3 * a) + i, static_cast<Eigen::Index>(3 * b) + j);
                        const double mv = me(static_cast<Eigen::Index>(3 * a) + i, static_cast<Eigen::Index>(3 * b) + j);
                        if (kv != 0.0) k_entries.emplace_back(r, c, kv);
                        if (mv != 0.0) m_entries.emplace_back(r, c, mv);
                    }
    };
    for (std::size_t t = 0; t < mesh.tets.size(); ++t) {
        const std::array<Eigen::Vector3d, 4> x = mesh.corners(t);
        const std::array<double, 4> phi = phi_of(t);
        std::vector<std::size_t> blocks;
        for (std::uint32_t node : mesh.tets[t]) blocks.push_back(3 * std::size_t{node});
        const TetGeometry g = tet_geometry(x);
        for (std::uint32_t node : mesh.tets[t]) support[node] += g.volume;
        if (!is_cut(phi)) {
            add(tet_stiffness(g, lame), tet_mass(g, density), blocks);
            continue;
        }
        ++out.cut_tets;
        const CutTet c = cut_tet(x, phi, k, lame, density, fitting);
        for (int i = 0; i < 4; ++i) {
            const std::uint32_t node = mesh.tets[t][static_cast<std::size_t>(i)];
            blocks.push_back(3 * (n + static_cast<std::size_t>(out.enriched[node])));
            across[node] += c.side_volume[c.node_side[static_cast<std::size_t>(i)] ? 0 : 1];
        }
        add(c.stiffness, c.mass, blocks);
    }
    out.stiffness.resize(static_cast<Eigen::Index>(dofs), static_cast<Eigen::Index>(dofs));
    out.stiffness.setFromTriplets(k_entries.begin(), k_entries.end());
    out.mass.resize(static_cast<Eigen::Index>(dofs), static_cast<Eigen::Index>(dofs));
    out.mass.setFromTriplets(m_entries.begin(), m_entries.end());
    out.volume_ratio.assign(dofs, 1.0);
    out.weighted_ratio.assign(dofs, 1.0);
    const Eigen::VectorXd mass_diagonal = out.mass.diagonal();
    for (std::size_t node = 0; node < n; ++node)
        if (out.enriched[node] >= 0)
            for (std::size_t i = 0; i < 3; ++i) {
                const std::size_t d = 3 * (n + static_cast<std::size_t>(out.enriched[node])) + i;
                out.volume_ratio[d] = across[node] / support[node];
                out.weighted_ratio[d] = mass_diagonal[static_cast<Eigen::Index>(d)] / mass_diagonal[static_cast<Eigen::Index>(3 * node + i)];
            }
    return out;
}

} // namespace vox::isxfem
