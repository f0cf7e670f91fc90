#pragma once
// The global stiffness and consistent mass of a tetrahedral mesh cut through by a plane, with the
// Is-XFEM enrichment: every tetrahedron with nodes on both sides of the plane is cut whole, and
// each of its nodes gets three enriched dofs (appended after the 3 n standard ones). The volume
// ratio of an enriched node (the paper's equation 17) is the share of its support that lies across
// the cut from it: where the k = 0 enrichment lives, and what goes to zero when the cut passes
// close to the node.

#include "isxfem/tet_mesh.hpp"

#include "grid/hex8.hpp"

#include <Eigen/SparseCore>

#include <cstdint>
#include <vector>

namespace vox::isxfem {

/// phi(x) = normal . x - offset (x in world m); the positive side is phi >= 0.
struct PlaneCut {
    Eigen::Vector3d normal = Eigen::Vector3d::UnitX();
    double offset = 0.0;
    [[nodiscard]] double at(const Eigen::Vector3d& x) const { return normal.dot(x) - offset; }
};

struct PlaneCutSystem {
    Eigen::SparseMatrix<double> stiffness, mass; ///< N/m and kg; 3 (nodes + enriched nodes) square
    std::vector<std::int32_t> enriched;          ///< per node: its place among the enriched nodes, or -1
    std::vector<double> volume_ratio;            ///< per dof: enriched ones their node's ratio, standard ones 1
    /// Per dof: for enriched ones int (psi_i N_i)^2 / int N_i^2 over the node's support (the
    /// ratio of their consistent-mass diagonals), a volume ratio weighted by what the enriched
    /// function actually is: for k = 0 it is small where the plain ratio is, for k > 0 it stays
    /// near k^2 on the node's own side; standard dofs 1.
    std::vector<double> weighted_ratio;
    std::size_t cut_tets = 0;
    [[nodiscard]] std::size_t dofs() const { return volume_ratio.size(); }
};

PlaneCutSystem assemble_plane_cut(const TetMesh& mesh, const PlaneCut& cut, double k, const grid::Lame& lame, double density);

} // namespace vox::isxfem
