#include "isxfem/xfem_tetrahedron.hpp"

#include "isxfem/cut_tetrahedron.hpp"
#include "isxfem/simplex_rule.hpp"

#include <Eigen/LU>

#include <cmath>
#include <stdexcept>

namespace vox::isxfem {
namespace {

/// The 3 x 3 block of the isotropic stiffness integrand between basis functions with gradients
/// ga and gb: lambda ga gb^T + mu (gb ga^T + (ga . gb) I).
Eigen::Matrix3d elastic_block(const Eigen::Vector3d& ga, const Eigen::Vector3d& gb, const grid::Lame& lame)
{
    return lame.lambda * ga * gb.transpose() + lame.mu * (gb * ga.transpose() + ga.dot(gb) * Eigen::Matrix3d::Identity());
}

/// The element's basis at a point with barycentric coordinates n in region `pattern` (bit j: the
/// side of cut j): N_c, then per cut psi_jc N_c, and their gradients (equation 3, added per cut).
void basis_at(const std::array<double, 4>& n, const TetGeometry& g, const std::vector<std::array<unsigned char, 4>>& node_side,
              const std::vector<Eigen::Vector3d>& grad_gamma, unsigned pattern, double k, std::vector<double>& value,
              std::vector<Eigen::Vector3d>& grad)
{
    const std::size_t cuts = node_side.size();
    value.resize(4 + 4 * cuts);
    grad.resize(4 + 4 * cuts);
    for (std::size_t c = 0; c < 4; ++c) {
        value[c] = n[c];
        grad[c] = g.gradient.row(static_cast<Eigen::Index>(c)).transpose();
    }
    for (std::size_t j = 0; j < cuts; ++j) {
        double gamma = 0.0;
        for (std::size_t m = 0; m < 4; ++m) gamma += node_side[j][m] * n[m];
        const double h = (pattern >> j) & 1u;
        for (std::size_t c = 0; c < 4; ++c) {
            const double psi = h - (k * gamma + (1.0 - k) * node_side[j][c]);
            value[4 + 4 * j + c] = psi * n[c];
            grad[4 + 4 * j + c] = psi * grad[c] - k * n[c] * grad_gamma[j];
        }
    }
}

/// Adds a quadrature point's stiffness and consistent-mass integrands, times `weight`.
template <class Matrix>
void add_point(double weight, const std::vector<double>& value, const std::vector<Eigen::Vector3d>& grad, const grid::Lame& lame,
               double density, Matrix& stiffness, Matrix& mass)
{
    for (std::size_t a = 0; a < value.size(); ++a)
        for (std::size_t b = 0; b < value.size(); ++b) {
            const auto ia = static_cast<Eigen::Index>(3 * a), ib = static_cast<Eigen::Index>(3 * b);
            stiffness.template block<3, 3>(ia, ib) += weight * elastic_block(grad[a], grad[b], lame);
            mass.template block<3, 3>(ia, ib).diagonal().array() += weight * density * value[a] * value[b];
        }
}

/// Per cut, the gradient of gamma_j = sum_m H_jm N_m.
std::vector<Eigen::Vector3d> gamma_gradients(const TetGeometry& g, const std::vector<std::array<unsigned char, 4>>& node_side)
{
    std::vector<Eigen::Vector3d> out(node_side.size(), Eigen::Vector3d::Zero());
    for (std::size_t j = 0; j < node_side.size(); ++j)
        for (std::size_t c = 0; c < 4; ++c)
            if (node_side[j][c]) out[j] += g.gradient.row(static_cast<Eigen::Index>(c)).transpose();
    return out;
}

/// The parts of `pieces` (reference coordinates) on one side of the linear function with values
/// `phi` at the reference vertices.
std::vector<Piece> clip(const std::vector<Piece>& pieces, const std::array<double, 4>& phi, bool positive)
{
    std::vector<Piece> out;
    for (const Piece& p : pieces) {
        std::array<double, 4> at{}; // phi at the piece's corners
        for (int k = 0; k < 4; ++k) {
            const Eigen::Vector3d xi = k == 0 ? p.corner : Eigen::Vector3d(p.corner + p.edges.col(k - 1));
            const std::array<double, 4> n{1.0 - xi.sum(), xi.x(), xi.y(), xi.z()};
            for (std::size_t l = 0; l < 4; ++l) at[static_cast<std::size_t>(k)] += n[l] * phi[l];
        }
        const CutSides sides = split_reference_tetrahedron(at);
        for (const Piece& s : positive ? sides.positive : sides.negative) {
            Piece q;
            q.corner = p.corner + p.edges * s.corner;
            q.edges = p.edges * s.edges;
            q.volume = 6.0 * p.volume * s.volume;
            if (q.volume > 0.0) out.push_back(q);
        }
    }
    return out;
}

} // namespace

TetGeometry tet_geometry(const std::array<Eigen::Vector3d, 4>& x)
{
    Eigen::Matrix3d j;
    for (int k = 0; k < 3; ++k) j.col(k) = x[static_cast<std::size_t>(k + 1)] - x[0];
    const double det = j.determinant();
    if (!(std::abs(det) > 0.0)) throw std::invalid_argument("tet_geometry: a degenerate tetrahedron");
    // Rows 1..3 of the gradient are the rows of J^-1 (N_k = xi_k); row 0 is minus their sum.
    const Eigen::Matrix3d inverse = j.inverse();
    TetGeometry g;
    g.gradient.bottomRows<3>() = inverse;
    g.gradient.row(0) = -inverse.colwise().sum();
    g.volume = std::abs(det) / 6.0;
    return g;
}

Matrix12d tet_stiffness(const TetGeometry& g, const grid::Lame& lame)
{
    Matrix12d k;
    for (int a = 0; a < 4; ++a)
        for (int b = 0; b < 4; ++b)
            k.block<3, 3>(3 * a, 3 * b) = g.volume * elastic_block(g.gradient.row(a).transpose(), g.gradient.row(b).transpose(), lame);
    return k;
}

Matrix12d tet_mass(const TetGeometry& g, double density)
{
    Matrix12d m = Matrix12d::Zero();
    for (int a = 0; a < 4; ++a)
        for (int b = 0; b < 4; ++b) m.block<3, 3>(3 * a, 3 * b).diagonal().setConstant(density * g.volume * (a == b ? 2.0 : 1.0) / 20.0);
    return m;
}

CutTet cut_tet(const std::array<Eigen::Vector3d, 4>& x, const std::array<double, 4>& phi, double k, const grid::Lame& lame,
               double density, const MomentFitting& fitting)
{
    if (!(k >= 0.0 && k <= 1.0)) throw std::invalid_argument("cut_tet: k must be in [0, 1]");
    const TetGeometry g = tet_geometry(x);
    const SideWeights w = side_weights(fitting, phi);
    CutTet out;
    out.side_volume = {6.0 * g.volume * w.negative_volume, 6.0 * g.volume * w.positive_volume};
    for (int i = 0; i < 4; ++i) out.node_side[static_cast<std::size_t>(i)] = phi[static_cast<std::size_t>(i)] >= 0.0 ? 1 : 0;
    const std::vector<std::array<unsigned char, 4>> node_side{out.node_side};
    const std::vector<Eigen::Vector3d> grad_gamma = gamma_gradients(g, node_side);
    std::vector<double> value;
    std::vector<Eigen::Vector3d> grad;
    for (unsigned side = 0; side < 2; ++side) {
        const Eigen::VectorXd& weights = side == 0 ? w.negative : w.positive;
        for (std::size_t q = 0; q < fitting.points().size(); ++q) {
            const Eigen::Vector3d& xi = fitting.points()[q];
            basis_at({1.0 - xi.sum(), xi.x(), xi.y(), xi.z()}, g, node_side, grad_gamma, side, k, value, grad);
            add_point(6.0 * g.volume * weights[static_cast<Eigen::Index>(q)], value, grad, lame, density, out.side_stiffness[side], out.mass);
        }
    }
    out.stiffness = out.side_stiffness[0] + out.side_stiffness[1];
    return out;
}

MultiCutTet multi_cut_tet(const std::array<Eigen::Vector3d, 4>& x, const std::vector<std::array<double, 4>>& phi, double k,
                          const grid::Lame& lame, double density)
{
    if (!(k >= 0.0 && k <= 1.0)) throw std::invalid_argument("multi_cut_tet: k must be in [0, 1]");
    const TetGeometry g = tet_geometry(x);
    const std::size_t cuts = phi.size(), blocks = 4 + 4 * cuts;
    const auto n_dofs = static_cast<Eigen::Index>(3 * blocks);
    MultiCutTet out;
    out.mass = Eigen::MatrixXd::Zero(n_dofs, n_dofs);
    out.node_side.resize(cuts);
    for (std::size_t j = 0; j < cuts; ++j)
        for (std::size_t c = 0; c < 4; ++c) out.node_side[j][c] = phi[j][c] >= 0.0 ? 1 : 0;
    const std::vector<Eigen::Vector3d> grad_gamma = gamma_gradients(g, out.node_side);
    const SimplexRule rule = grundmann_moeller_tetrahedron(2); // degree 5: the mass's integrands are of degree 4
    std::vector<double> value;
    std::vector<Eigen::Vector3d> grad;
    for (unsigned pattern = 0; pattern < (1u << cuts); ++pattern) {
        std::vector<Piece> pieces{whole_tetrahedron()};
        for (std::size_t j = 0; j < cuts && !pieces.empty(); ++j) pieces = clip(pieces, phi[j], (pattern >> j) & 1u);
        Region region;
        region.pattern = pattern;
        for (const Piece& p : pieces) region.volume += 6.0 * g.volume * p.volume;
        if (!(region.volume > 0.0)) continue;
        region.stiffness = Eigen::MatrixXd::Zero(n_dofs, n_dofs);
        for (const Piece& p : pieces)
            for (std::size_t q = 0; q < rule.points.size(); ++q) {
                const Eigen::Vector3d xi = p.corner + p.edges * rule.points[q];
                basis_at({1.0 - xi.sum(), xi.x(), xi.y(), xi.z()}, g, out.node_side, grad_gamma, pattern, k, value, grad);
                add_point(6.0 * g.volume * 6.0 * p.volume * rule.weights[q], value, grad, lame, density, region.stiffness, out.mass);
            }
        out.regions.push_back(std::move(region));
    }
    return out;
}

} // namespace vox::isxfem
