#pragma once
// A tetrahedral model that can be cut without remeshing (Is-XFEM): the mesh at rest, a material per
// tetrahedron, and the cuts made so far. A cut goes along a plane or a blade's swept surface
// (isxfem/cut_surface.hpp); it is planar inside each tetrahedron it crosses (the level function
// interpolated from the tetrahedron's nodes, the same at a node for all its tetrahedra, so the
// crack is continuous), and is kept only where it separates the tetrahedron whole: every edge
// whose nodes lie on two sides is met by the cut's surface, a closed boundary through the element.
// Each node of a tetrahedron cut by cut j gets a block of three enriched dofs for j; dof blocks
// are numbered after the nodes' own, so the system grows and nothing is remeshed.
//
// Up to two cuts per tetrahedron, their enrichments added (Koschier et al. 2017). Each point of a
// tetrahedron lies in a region, its side of each of the tetrahedron's cuts (a bit each), and the
// field there is the nodes' plus each cut's enrichment on its side. Two cuts that do not cross
// inside a tetrahedron leave three regions, which the added enrichments separate whole; two that
// cross leave four, and three linear fields cannot move four pieces independently: those
// tetrahedra keep their pieces coupled, and the report counts them (`crossed_tets`) so the
// caller can say so. A third cut through a tetrahedron is not applied there (counted too), nor a
// second that runs alongside the first within it, leaving a region under 1 % of the tetrahedron
// between them (a blade drawn again along its crack), which the earlier crack is taken to separate.

#include "isxfem/cut_surface.hpp"
#include "isxfem/moment_fitting.hpp"
#include "isxfem/plane_cut_system.hpp"
#include "isxfem/tet_mesh.hpp"
#include "grid/elastic_material.hpp"
#include "isxfem/xfem_tetrahedron.hpp"

#include <functional>
#include <unordered_map>
#include <vector>

namespace vox::isxfem {

/// The most cuts a tetrahedron takes (its dof blocks: 4 per node set, 4 + 4 k_max_cuts in all).
constexpr std::size_t k_max_cuts = 2;
constexpr std::size_t k_max_blocks = 4 + 4 * k_max_cuts;

/// A cut through an element: its id, its level function and the sides of the element's nodes
/// (H_i = 1 where phi >= 0), and the dof blocks of the nodes' enrichment for it.
struct ElementCut {
    int id = -1;
    std::array<double, 4> phi{};
    std::array<unsigned char, 4> node_side{};
    std::array<std::uint32_t, 4> enriched{};
};

/// One tetrahedron of the model, with its matrices at rest.
struct XfemElement {
    std::array<std::uint32_t, 4> node{};
    TetGeometry geometry;
    std::uint32_t material = 0;
    std::vector<ElementCut> cuts;            ///< in the order they came (at most k_max_cuts)
    std::vector<Region> regions;             ///< cut: its non-empty regions
    bool crossed = false;                    ///< two cuts cross inside: four pieces, not all separable
    bool cut_left_out = false;               ///< a further cut went through it whole after its k_max_cuts: left out here
    bool left_to_earlier_cut = false;        ///< a second cut ran alongside its first too close: left to the first
    Matrix12d stiffness = Matrix12d::Zero(); ///< whole: K at rest
    Eigen::MatrixXd mass;                    ///< consistent mass over its dofs, kg
    [[nodiscard]] bool is_cut() const { return !cuts.empty(); }
    /// The place of cut `id` among its cuts, or -1.
    [[nodiscard]] int cut_index(int id) const
    {
        for (std::size_t j = 0; j < cuts.size(); ++j)
            if (cuts[j].id == id) return static_cast<int>(j);
        return -1;
    }
    /// Cut j's level function at the point with barycentric coordinates `bary`.
    [[nodiscard]] double level_at(std::size_t j, const std::array<double, 4>& bary) const
    {
        double phi = 0.0;
        for (std::size_t c = 0; c < 4; ++c) phi += bary[c] * cuts[j].phi[c];
        return phi;
    }
    /// The region of the point with barycentric coordinates `bary` (0 when uncut).
    [[nodiscard]] unsigned region_at(const std::array<double, 4>& bary) const
    {
        unsigned pattern = 0;
        for (std::size_t j = 0; j < cuts.size(); ++j)
            if (level_at(j, bary) >= 0.0) pattern |= 1u << j;
        return pattern;
    }
    /// The region node c lies in.
    [[nodiscard]] unsigned node_region(std::size_t c) const
    {
        unsigned pattern = 0;
        for (std::size_t j = 0; j < cuts.size(); ++j) pattern |= static_cast<unsigned>(cuts[j].node_side[c]) << j;
        return pattern;
    }
    /// Node c as region `pattern` sees it, from the dof blocks' values x: x_c + sum over the cuts of
    /// (h_j - H_jc) a_jc (the region's linear field; exact for k = 0).
    [[nodiscard]] Eigen::Vector3d region_node(std::size_t c, unsigned pattern, const std::vector<Eigen::Vector3d>& x) const
    {
        Eigen::Vector3d p = x[node[c]];
        for (std::size_t j = 0; j < cuts.size(); ++j)
            p += (static_cast<double>((pattern >> j) & 1u) - cuts[j].node_side[c]) * x[cuts[j].enriched[c]];
        return p;
    }
    /// Dof blocks of the element's shape functions: its 4 nodes, then each cut's enrichment of them.
    [[nodiscard]] std::size_t block_count() const { return 4 + 4 * cuts.size(); }
    [[nodiscard]] std::uint32_t block(std::size_t a) const { return a < 4 ? node[a] : cuts[(a - 4) / 4].enriched[(a - 4) % 4]; }
};

struct CutReport {
    int cut = -1;                   ///< the cut's id (-1: nothing was cut)
    std::size_t cut_tets = 0;       ///< newly cut (by this cut)
    std::size_t recut_tets = 0;     ///< of them, cut before by another cut: now twice
    std::size_t crossed_tets = 0;   ///< of those, where the two cuts cross inside: pieces left coupled
    std::size_t new_blocks = 0;     ///< enriched dof blocks added
    std::size_t partial_tets = 0;   ///< crossed but not separated whole (or only touched): left uncut
    std::size_t already_cut = 0;    ///< crossed whole but cut k_max_cuts times before: left as they were (XfemElement::cut_left_out)
    std::size_t beside_earlier = 0; ///< cut once before along nearly the same surface (under 1 % between): left to the earlier crack, counted once
};

class XfemModel {
public:
    /// `material`: per tetrahedron an index into `materials`. `k`: the Is-XFEM parameter in [0, 1]
    /// (0: standard XFEM).
    XfemModel(TetMesh mesh, std::vector<grid::ElasticMaterial> materials, std::vector<std::uint32_t> material, double k);

    /// Cuts by the plane where it crosses a tetrahedron whole within the region `inside` (a
    /// point of the plane, world m; all of the plane when null). `extend`: the id of an earlier
    /// cut that this one continues (a blade going on through its stroke; its own plane is kept and
    /// `plane` is not used), whose nodes keep their enriched blocks, so the crack stays one
    /// surface; -1: a new cut.
    CutReport cut(const PlaneCut& plane, const std::function<bool(const Eigen::Vector3d&)>& inside = {}, int extend = -1);
    /// Cuts along a swept surface where it goes through a tetrahedron whole. Its patches from
    /// `new_from` on are new since the last call for this stroke (only the tetrahedra they reach
    /// can have become whole); with `extend`, the surface replaces that cut's (it is the same
    /// stroke, grown).
    CutReport cut(const CutSurface& surface, std::size_t new_from, int extend = -1);

    [[nodiscard]] const TetMesh& mesh() const { return m_mesh; }
    [[nodiscard]] const std::vector<XfemElement>& elements() const { return m_elements; }
    [[nodiscard]] const std::vector<grid::ElasticMaterial>& materials() const { return m_materials; }
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
    /// The surface cut `id` went along.
    [[nodiscard]] const CutSurface& cut_surface(int id) const { return m_surfaces.at(static_cast<std::size_t>(id)); }
    /// Cut `id`'s level at a node: as the cut fixed it where it cut a tetrahedron of the node, its
    /// surface's elsewhere.
    [[nodiscard]] double node_level(int id, std::uint32_t node) const;
    /// Cut `id`'s level function at the point with barycentric coordinates `bary` in tetrahedron
    /// `tet`: interpolated from its nodes' levels (continuous from tetrahedron to tetrahedron; in a
    /// tetrahedron the cut went through, its crack's).
    [[nodiscard]] double level(int id, std::size_t tet, const std::array<double, 4>& bary) const;
    /// The unit normal of cut `id` (towards its positive side) in tetrahedron `tet`: the gradient of
    /// its interpolated level (the surface's normal at the tetrahedron's middle where that is flat).
    [[nodiscard]] Eigen::Vector3d crack_normal(int id, std::size_t tet) const;
    /// The longest edge of the mesh's tetrahedra, m.
    [[nodiscard]] double longest_edge() const { return m_longest_edge; }

private:
    TetMesh m_mesh;
    std::vector<grid::ElasticMaterial> m_materials;
    double m_k;
    MomentFitting m_fitting;
    std::vector<XfemElement> m_elements;
    std::vector<std::uint32_t> m_enriched_node; ///< per enriched block
    std::vector<double> m_enriched_across;      ///< per enriched block: volume across its cut in its node's support, m^3
    std::vector<double> m_support;              ///< per node: volume of its tetrahedra, m^3
    std::vector<std::unordered_map<std::uint32_t, std::uint32_t>> m_cut_blocks; ///< per cut: node -> enriched block
    double m_longest_edge = 0.0;
    std::vector<CutSurface> m_surfaces;                                   ///< per cut
    std::vector<std::unordered_map<std::uint32_t, double>> m_node_levels; ///< per cut: node -> level, fixed once it cut with it

    using EdgeTest = std::function<bool(const Eigen::Vector3d& a, const Eigen::Vector3d& b, const Eigen::Vector3d& crossing)>;
    /// Cut `id` (extend: an existing one) along `surface` through the tetrahedra `candidate` lets
    /// through, where `covered` says each of a tetrahedron's edges with nodes on two sides is cut
    /// (its ends and the level's crossing point on it).
    CutReport cut_along(int id, bool extend, const CutSurface& surface, const std::function<bool(std::size_t)>& candidate,
                        const EdgeTest& covered);
    /// Leaves out of `candidates` (tetrahedra about to be cut by `id`, their levels in `phi`) those
    /// in islands of the crack: tetrahedra the surface crosses whole that lie within a tetrahedron
    /// of the rest of the crack but join it across no edge it crosses (counted as partial in
    /// `report`).
    void leave_out_islands(int id, std::vector<std::uint32_t>& candidates, std::vector<std::array<double, 4>>& phi, CutReport& report) const;
    int m_cuts = 0;
    std::size_t m_revision = 0;
};

} // namespace vox::isxfem
