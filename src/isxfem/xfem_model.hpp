#pragma once
// A tetrahedral model that can be cut without remeshing (Is-XFEM): the mesh at rest, a material per
// tetrahedron, and the cuts made so far. A cut is planar inside each tetrahedron it crosses and
// is kept only where it separates the tetrahedron whole (its crossing points on all the
// tetrahedron's cut edges lie inside the cut's region: a closed boundary through the element).
// Each node of a tetrahedron cut by cut j gets a block of three enriched dofs for j; dof blocks
// are numbered after the nodes' own, so the system grows and nothing is remeshed.
//
// One cut per tetrahedron for now: a second cut through an already cut tetrahedron is not applied
// there; the report counts those tetrahedra so the caller can show them.

#include "isxfem/moment_fitting.hpp"
#include "isxfem/plane_cut_system.hpp"
#include "isxfem/tet_mesh.hpp"
#include "isxfem/xfem_tetrahedron.hpp"

#include <functional>
#include <unordered_map>
#include <vector>

namespace vox::isxfem {

struct TetMaterial {
    grid::Lame lame;
    double density = 1000.0; ///< kg/m^3
};

/// One tetrahedron of the model, with its matrices at rest.
struct XfemElement {
    std::array<std::uint32_t, 4> node{};
    TetGeometry geometry;
    std::uint32_t material = 0;
    int cut = -1;                              ///< the cut through it, or -1
    std::array<std::uint32_t, 4> enriched{};   ///< dof blocks of its nodes' enrichment (when cut)
    std::array<double, 4> phi{};               ///< the cut's level function at its nodes
    std::array<unsigned char, 4> node_side{};  ///< H_i
    std::array<double, 2> side_volume{};       ///< m^3
    Matrix12d stiffness = Matrix12d::Zero();   ///< whole: K at rest
    std::array<Matrix24d, 2> side_stiffness{}; ///< cut: K of each side (negative, positive)
    Matrix24d mass = Matrix24d::Zero();        ///< cut: 24 x 24; whole: the top-left 12 x 12
    /// Dof blocks of the element's shape functions: its 4 nodes, then (cut) their enrichment.
    [[nodiscard]] std::size_t block_count() const { return cut >= 0 ? 8 : 4; }
    [[nodiscard]] std::uint32_t block(std::size_t a) const { return a < 4 ? node[a] : enriched[a - 4]; }
};

struct CutReport {
    int cut = -1;                   ///< the cut's id (-1: nothing was cut)
    std::size_t cut_tets = 0;       ///< newly cut
    std::size_t new_blocks = 0;     ///< enriched dof blocks added
    std::size_t partial_tets = 0;   ///< crossed but not separated whole (or only touched): left uncut
    std::size_t already_cut = 0;    ///< crossed but cut before by another cut: left as they were
};

class XfemModel {
public:
    /// `material`: per tetrahedron an index into `materials`. `k`: the Is-XFEM parameter in [0, 1]
    /// (0: standard XFEM).
    XfemModel(TetMesh mesh, std::vector<TetMaterial> materials, std::vector<std::uint32_t> material, double k);

    /// Cuts by the plane where it crosses a tetrahedron whole within the region `inside` (a
    /// point of the plane, world m; all of the plane when null). `extend`: the id of an earlier
    /// cut by the same plane that this one continues (a blade going on through its stroke), whose
    /// nodes keep their enriched blocks, so the crack stays one surface; -1: a new cut.
    CutReport cut(const PlaneCut& plane, const std::function<bool(const Eigen::Vector3d&)>& inside = {}, int extend = -1);

    [[nodiscard]] const TetMesh& mesh() const { return m_mesh; }
    [[nodiscard]] const std::vector<XfemElement>& elements() const { return m_elements; }
    [[nodiscard]] const std::vector<TetMaterial>& materials() const { return m_materials; }
    [[nodiscard]] double k() const { return m_k; }
    [[nodiscard]] std::size_t node_count() const { return m_mesh.nodes.size(); }
    /// Dof blocks (3 dofs each): the nodes', then the enriched ones.
    [[nodiscard]] std::size_t block_count() const { return m_mesh.nodes.size() + m_enriched_node.size(); }
    /// The node an enriched block belongs to (block >= node_count()).
    [[nodiscard]] std::uint32_t enriched_node(std::uint32_t block) const { return m_enriched_node[block - node_count()]; }
    [[nodiscard]] int cut_count() const { return m_cuts; }
    /// Counts the calls to cut() that cut something: what was derived from the cuts is stale
    /// when it changed.
    [[nodiscard]] std::size_t revision() const { return m_revision; }
    /// The volume ratio of a dof block (the sculpting paper's equation 17): for an enriched block,
    /// the share of its node's support that lies across the cut from the node, what the k = 0
    /// enrichment lives on and what goes to zero as a cut passes close to the node's far side;
    /// 1 for a node's own block.
    [[nodiscard]] double volume_ratio(std::uint32_t block) const
    {
        return block < node_count() ? 1.0 : m_enriched_across[block - node_count()] / m_support[enriched_node(block)];
    }
    /// The plane of cut `id`.
    [[nodiscard]] const PlaneCut& cut_plane(int id) const { return m_cut_planes.at(static_cast<std::size_t>(id)); }

private:
    TetMesh m_mesh;
    std::vector<TetMaterial> m_materials;
    double m_k;
    MomentFitting m_fitting;
    std::vector<XfemElement> m_elements;
    std::vector<std::uint32_t> m_enriched_node; ///< per enriched block
    std::vector<double> m_enriched_across;      ///< per enriched block: volume across its cut in its node's support, m^3
    std::vector<double> m_support;              ///< per node: volume of its tetrahedra, m^3
    std::vector<std::unordered_map<std::uint32_t, std::uint32_t>> m_cut_blocks; ///< per cut: node -> enriched block
    std::vector<PlaneCut> m_cut_planes;
    int m_cuts = 0;
    std::size_t m_revision = 0;
};

} // namespace vox::isxfem
