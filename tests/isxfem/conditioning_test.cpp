// The stability claim behind Is-XFEM, on a small bar held at both ends and cut through by a plane
// theta h from a node plane: the XFEM (k = 0) stiffness's condition number grows about three
// decades per decade of theta (the smallest side of a cut corner tetrahedron has volume theta^3),
// Is-XFEM's (k = 0.1) stays bounded, the paper's volume-ratio scaling repairs XFEM, and Jacobi
// scaling brings both within a few times the uncut bar. (`voxsculpt bench conditioning` measures
// the same on a larger bar, with the mass.)

#include "isxfem/plane_cut_system.hpp"
#include "isxfem/tet_mesh.hpp"

#include <Eigen/Eigenvalues>
#include <gtest/gtest.h>

#include <cmath>

using namespace vox;
using namespace vox::isxfem;

namespace {

constexpr double k_h = 0.01;
constexpr int k_cells = 6;

enum class Scaling { none, volume_ratio, jacobi };

double stiffness_condition(double theta, double k, Scaling scaling)
{
    const TetMesh bar = cube_lattice({k_cells, 2, 2}, k_h);
    const PlaneCut cut{Eigen::Vector3d::UnitX(), theta > 0.0 ? (k_cells / 2 + theta) * k_h : -1.0};
    const PlaneCutSystem s = assemble_plane_cut(bar, cut, k, grid::lame_from_young_poisson(1e5, 0.3), 1500.0);
    std::vector<Eigen::Index> free;
    for (std::size_t d = 0; d < s.dofs(); ++d) {
        const std::size_t node = d / 3;
        if (node >= bar.nodes.size() || (bar.nodes[node].x() > 1e-9 && bar.nodes[node].x() < k_cells * k_h - 1e-9))
            free.push_back(static_cast<Eigen::Index>(d));
    }
    const Eigen::MatrixXd full(s.stiffness);
    const auto n = static_cast<Eigen::Index>(free.size());
    Eigen::MatrixXd kf(n, n);
    for (Eigen::Index i = 0; i < n; ++i)
        for (Eigen::Index j = 0; j < n; ++j) kf(i, j) = full(free[static_cast<std::size_t>(i)], free[static_cast<std::size_t>(j)]);
    Eigen::VectorXd t = Eigen::VectorXd::Ones(n);
    for (Eigen::Index i = 0; i < n; ++i) {
        if (scaling == Scaling::volume_ratio) t[i] = 1.0 / std::sqrt(s.volume_ratio[static_cast<std::size_t>(free[static_cast<std::size_t>(i)])]);
        if (scaling == Scaling::jacobi) t[i] = 1.0 / std::sqrt(kf(i, i));
    }
    const Eigen::VectorXd e =
        Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd>(t.asDiagonal() * kf * t.asDiagonal(), Eigen::EigenvaluesOnly).eigenvalues();
    return e.maxCoeff() / e.minCoeff();
}

} // namespace

TEST(Conditioning, XfemDegradesIsXfemStaysBoundedScalingRepairs)
{
    const double uncut = stiffness_condition(0.0, 0.0, Scaling::none);
    const double xfem2 = stiffness_condition(1e-2, 0.0, Scaling::none), xfem3 = stiffness_condition(1e-3, 0.0, Scaling::none);
    const double is2 = stiffness_condition(1e-2, 0.1, Scaling::none), is3 = stiffness_condition(1e-3, 0.1, Scaling::none);
    EXPECT_GT(xfem3 / xfem2, std::pow(10.0, 2.5)); // about three decades a decade
    EXPECT_LT(is3 / is2, 1.5);                       // bounded
    EXPECT_LT(is3, 1000.0 * uncut);
    EXPECT_LT(stiffness_condition(1e-3, 0.0, Scaling::volume_ratio), 10.0 * uncut);
    // The volume ratio is no help to Is-XFEM: its enriched functions live on both sides.
    EXPECT_GT(stiffness_condition(1e-3, 0.1, Scaling::volume_ratio), 1e3 * is3);
    for (double k : {0.0, 0.1}) EXPECT_LT(stiffness_condition(1e-3, k, Scaling::jacobi), 10.0 * stiffness_condition(0.0, k, Scaling::jacobi));
}
