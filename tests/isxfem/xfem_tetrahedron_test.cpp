// Linear tetrahedra whole and cut with the Is-XFEM enrichment, and the plane-cut system:
//  - a whole tetrahedron: rigid motions cost nothing, a uniform strain costs V W(eps), the mass is
//    rho V;
//  - a cut one: its standard block is the whole tetrahedron's (the two sides add up); each side
//    translating alone costs nothing for every k; each side turning alone costs nothing for
//    k = 0 only (for k > 0 the enrichment cannot represent it: the spurious energy is measured);
//  - cut twice (regions clipped plane by plane, integrated directly): one cut gives what moment
//    fitting gives; the regions' volumes and the standard blocks add up to the whole; each of
//    the three pieces two parallel cuts leave translates alone at no cost;
//  - the lattice is conforming and fills its box;
//  - a bar cut through falls apart into two pieces: 12 zero-energy modes for k = 0 (two rigid
//    bodies), 9 for k > 0 (the relative rotation is held), 6 uncut.

#include "isxfem/plane_cut_system.hpp"
#include "isxfem/tet_mesh.hpp"
#include "isxfem/xfem_tetrahedron.hpp"

#include <Eigen/Eigenvalues>
#include <Eigen/Geometry>
#include <gtest/gtest.h>

#include <algorithm>
#include <functional>
#include <cmath>
#include <map>
#include <random>

using namespace vox;
using namespace vox::isxfem;

namespace {

const grid::Lame k_lame = grid::lame_from_young_poisson(1e5, 0.3);
constexpr double k_density = 1500.0;

std::array<Eigen::Vector3d, 4> random_tet(std::mt19937& rng)
{
    std::uniform_real_distribution<double> u(-0.01, 0.01);
    std::array<Eigen::Vector3d, 4> x;
    do {
        for (Eigen::Vector3d& p : x) p = {u(rng), u(rng), u(rng)};
    } while (signed_volume(x) < 2e-7);
    return x;
}

/// Nodal values of the field f at the corners, node-major.
Eigen::Matrix<double, 12, 1> sample(const std::array<Eigen::Vector3d, 4>& x, const std::function<Eigen::Vector3d(const Eigen::Vector3d&)>& f)
{
    Eigen::Matrix<double, 12, 1> v;
    for (int c = 0; c < 4; ++c) v.segment<3>(3 * c) = f(x[static_cast<std::size_t>(c)]);
    return v;
}

/// A cut that separates nodes {0} or {0, 1} from the others (plane through the given points).
std::array<double, 4> cut_levels(const std::array<Eigen::Vector3d, 4>& x, bool two_two)
{
    const Eigen::Vector3d near = two_two ? Eigen::Vector3d(0.5 * (x[0] + x[1])) : x[0];
    const Eigen::Vector3d far = two_two ? Eigen::Vector3d(0.5 * (x[2] + x[3])) : Eigen::Vector3d((x[1] + x[2] + x[3]) / 3.0);
    const Eigen::Vector3d n = (far - near).normalized();
    const double offset = n.dot(near + 0.37 * (far - near));
    std::array<double, 4> phi{};
    for (int c = 0; c < 4; ++c) phi[static_cast<std::size_t>(c)] = n.dot(x[static_cast<std::size_t>(c)]) - offset;
    return phi;
}

} // namespace

TEST(XfemTetrahedron, WholeTetrahedronMechanics)
{
    std::mt19937 rng(5);
    const auto x = random_tet(rng);
    const TetGeometry g = tet_geometry(x);
    EXPECT_NEAR(g.volume, signed_volume(x), 1e-20);
    const Matrix12d k = tet_stiffness(g, k_lame);
    const Eigen::Vector3d w(0.3, -0.2, 0.5);
    for (const auto& rigid : {sample(x, [](const Eigen::Vector3d&) { return Eigen::Vector3d(1, 2, 3); }),
                              sample(x, [&](const Eigen::Vector3d& p) { return Eigen::Vector3d(w.cross(p)); })})
        EXPECT_LT((k * rigid).norm(), 1e-9 * k.norm() * rigid.norm());
    Eigen::Matrix3d eps;
    eps << 1e-3, 2e-4, 0, 2e-4, -5e-4, 1e-4, 0, 1e-4, 3e-4;
    const auto u = sample(x, [&](const Eigen::Vector3d& p) { return Eigen::Vector3d(eps * p); });
    const double energy_density = k_lame.mu * eps.squaredNorm() + 0.5 * k_lame.lambda * eps.trace() * eps.trace();
    EXPECT_NEAR(0.5 * u.dot(k * u), g.volume * energy_density, 1e-10 * g.volume * energy_density);
    const Matrix12d m = tet_mass(g, k_density);
    Eigen::Matrix<double, 12, 1> ones_x = Eigen::Matrix<double, 12, 1>::Zero();
    for (int c = 0; c < 4; ++c) ones_x[3 * c] = 1.0;
    EXPECT_NEAR(ones_x.dot(m * ones_x), k_density * g.volume, 1e-12 * k_density * g.volume);
}

TEST(XfemTetrahedron, SidesAddUpAndSidesMoveApart)
{
    const MomentFitting fitting;
    std::mt19937 rng(9);
    for (bool two_two : {false, true})
        for (double k : {0.0, 0.1, 1.0}) {
            SCOPED_TRACE(std::string(two_two ? "2-2" : "1-3") + " cut, k = " + std::to_string(k));
            const auto x = random_tet(rng);
            const auto phi = cut_levels(x, two_two);
            const CutTet c = cut_tet(x, phi, k, k_lame, k_density, fitting);
            const TetGeometry g = tet_geometry(x);
            EXPECT_LT((c.stiffness.topLeftCorner<12, 12>() - tet_stiffness(g, k_lame)).norm(), 1e-12 * tet_stiffness(g, k_lame).norm());
            EXPECT_LT((c.mass.topLeftCorner<12, 12>() - tet_mass(g, k_density)).norm(), 1e-12 * tet_mass(g, k_density).norm());
            EXPECT_NEAR(c.side_volume[0] + c.side_volume[1], g.volume, 1e-15 * g.volume);
            EXPECT_GT(Eigen::SelfAdjointEigenSolver<Matrix24d>(c.stiffness).eigenvalues().minCoeff(), -1e-10 * c.stiffness.norm());
            EXPECT_GT(Eigen::SelfAdjointEigenSolver<Matrix24d>(c.mass).eigenvalues().minCoeff(), -1e-10 * c.mass.norm());

            // The positive side moves by f(x), the negative side stays: u_i = H_i f(x_i), a_i = f(x_i).
            auto piece_motion = [&](const std::function<Eigen::Vector3d(const Eigen::Vector3d&)>& f) {
                Eigen::Matrix<double, 24, 1> v;
                for (int i = 0; i < 4; ++i) {
                    v.segment<3>(3 * i) = c.node_side[static_cast<std::size_t>(i)] * f(x[static_cast<std::size_t>(i)]);
                    v.segment<3>(12 + 3 * i) = f(x[static_cast<std::size_t>(i)]);
                }
                return v;
            };
            const auto translate = piece_motion([](const Eigen::Vector3d&) { return Eigen::Vector3d(1e-3, -2e-3, 5e-4); });
            EXPECT_LT(translate.dot(c.stiffness * translate), 1e-12 * c.stiffness.norm() * translate.squaredNorm());
            const Eigen::Vector3d w(0.02, -0.01, 0.03);
            const auto turn = piece_motion([&](const Eigen::Vector3d& p) { return Eigen::Vector3d(w.cross(p)); });
            const double turn_energy = 0.5 * turn.dot(c.stiffness * turn);
            // Reference: the same turn as a strain of the whole tetrahedron, (w x) sym part is
            // zero, so compare with a stretch of the same size.
            const auto stretch = sample(x, [&](const Eigen::Vector3d& p) { return Eigen::Vector3d(w.norm() * p.x(), 0, 0); });
            const double stretch_energy = 0.5 * stretch.dot(tet_stiffness(g, k_lame) * stretch);
            if (k == 0.0)
                EXPECT_LT(turn_energy, 1e-12 * stretch_energy);
            else
                EXPECT_GT(turn_energy, 1e-4 * k * k * stretch_energy); // held: the enrichment cannot turn a piece
        }
}

TEST(XfemTetrahedron, RegionsOfOneCutMatchMomentFitting)
{
    const MomentFitting fitting;
    std::mt19937 rng(21);
    for (bool two_two : {false, true}) {
        const auto x = random_tet(rng);
        const auto phi = cut_levels(x, two_two);
        const CutTet fitted = cut_tet(x, phi, 0.1, k_lame, k_density, fitting);
        const MultiCutTet direct = multi_cut_tet(x, {phi}, 0.1, k_lame, k_density);
        ASSERT_EQ(direct.regions.size(), 2u);
        for (const Region& r : direct.regions) {
            EXPECT_NEAR(r.volume, fitted.side_volume[r.pattern], 1e-13 * tet_geometry(x).volume);
            EXPECT_LT((r.stiffness - fitted.side_stiffness[r.pattern]).norm(), 1e-10 * fitted.stiffness.norm()) << "region " << r.pattern;
        }
        EXPECT_LT((direct.mass - fitted.mass).norm(), 1e-10 * fitted.mass.norm());
    }
}

TEST(XfemTetrahedron, TwoCutsLeaveRegionsThatAddUpAndMoveApart)
{
    std::mt19937 rng(5);
    const auto x = random_tet(rng);
    const TetGeometry g = tet_geometry(x);
    const Eigen::Vector3d n = (x[1] - x[0]).normalized();
    // Two parallel planes through the tetrahedron (a third and two thirds of the way along n
    // between its extreme corners): three regions.
    double lo = INFINITY, hi = -INFINITY;
    for (const Eigen::Vector3d& p : x) {
        lo = std::min(lo, n.dot(p));
        hi = std::max(hi, n.dot(p));
    }
    std::vector<std::array<double, 4>> phi(2);
    for (std::size_t j = 0; j < 2; ++j)
        for (std::size_t c = 0; c < 4; ++c) phi[j][c] = n.dot(x[c]) - (lo + (j + 1.0) / 3.0 * (hi - lo));
    for (double k : {0.0, 0.1}) {
        SCOPED_TRACE("k = " + std::to_string(k));
        const MultiCutTet m = multi_cut_tet(x, phi, k, k_lame, k_density);
        ASSERT_EQ(m.regions.size(), 3u); // past the second plane means past the first: no region 2 (10b)
        Eigen::MatrixXd total = Eigen::MatrixXd::Zero(36, 36);
        double volume = 0.0;
        for (const Region& r : m.regions) {
            total += r.stiffness;
            volume += r.volume;
            EXPECT_NE(r.pattern, 2u);
        }
        EXPECT_NEAR(volume, g.volume, 1e-14 * g.volume);
        EXPECT_LT((total.topLeftCorner(12, 12) - tet_stiffness(g, k_lame)).norm(), 1e-10 * tet_stiffness(g, k_lame).norm());
        EXPECT_LT((m.mass.topLeftCorner(12, 12) - tet_mass(g, k_density)).norm(), 1e-10 * tet_mass(g, k_density).norm());
        EXPECT_GT(Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd>(total).eigenvalues().minCoeff(), -1e-10 * total.norm());
        EXPECT_GT(Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd>(m.mass).eigenvalues().minCoeff(), -1e-10 * m.mass.norm());
        // Each piece translating alone by t, the others still. With T_q the target of region q,
        // a_0 = T_1 - T_0 and a_1 = T_3 - T_1 at every node, u_c = T_0 + H_0c a_0 + H_1c a_1: the
        // field is then T_0 + sum_j h_j a_j in each region, for any k (the gamma terms of a
        // constant jump cancel).
        const Eigen::Vector3d t(1e-3, -2e-3, 5e-4);
        for (unsigned piece : {0u, 1u, 3u}) {
            auto target = [&](unsigned q) { return q == piece ? t : Eigen::Vector3d::Zero(); };
            const Eigen::Vector3d a0 = target(1) - target(0), a1 = target(3) - target(1);
            Eigen::VectorXd v(36);
            for (std::size_t c = 0; c < 4; ++c) {
                const auto i3 = static_cast<Eigen::Index>(3 * c);
                v.segment<3>(i3) = target(0) + m.node_side[0][c] * a0 + m.node_side[1][c] * a1;
                v.segment<3>(12 + i3) = a0;
                v.segment<3>(24 + i3) = a1;
            }
            EXPECT_LT(v.dot(total * v), 1e-12 * total.norm() * v.squaredNorm()) << "piece " << piece;
        }
    }
}

TEST(TetMesh, CubeLatticeIsConformingAndFillsItsBox)
{
    const TetMesh mesh = cube_lattice({3, 2, 2}, 0.01);
    EXPECT_EQ(mesh.nodes.size(), 4u * 3u * 3u);
    EXPECT_EQ(mesh.tets.size(), 6u * 12u);
    double volume = 0.0;
    std::map<std::array<std::uint32_t, 3>, int> faces;
    for (std::size_t t = 0; t < mesh.tets.size(); ++t) {
        const double v = signed_volume(mesh.corners(t));
        EXPECT_GT(v, 0.0);
        volume += v;
        for (int skip = 0; skip < 4; ++skip) {
            std::array<std::uint32_t, 3> f{};
            int k = 0;
            for (int c = 0; c < 4; ++c)
                if (c != skip) f[static_cast<std::size_t>(k++)] = mesh.tets[t][static_cast<std::size_t>(c)];
            std::sort(f.begin(), f.end());
            ++faces[f];
        }
    }
    EXPECT_NEAR(volume, 0.03 * 0.02 * 0.02, 1e-15);
    int boundary = 0;
    for (const auto& [f, count] : faces) {
        EXPECT_LE(count, 2);
        boundary += count == 1;
    }
    EXPECT_EQ(boundary, 2 * 2 * (3 * 2 + 3 * 2 + 2 * 2)); // two triangles per boundary square
}

TEST(PlaneCutSystem, ABarCutThroughComesApart)
{
    const TetMesh bar = cube_lattice({4, 1, 1}, 0.01);
    auto zero_modes = [](const PlaneCutSystem& s) {
        const Eigen::VectorXd e = Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd>(Eigen::MatrixXd(s.stiffness)).eigenvalues();
        return static_cast<int>((e.array().abs() < 1e-9 * e.maxCoeff()).count());
    };
    const PlaneCut cut{Eigen::Vector3d(1, 0.1, -0.05).normalized(), 0.0213};
    const PlaneCutSystem k0 = assemble_plane_cut(bar, cut, 0.0, k_lame, k_density);
    const PlaneCutSystem k01 = assemble_plane_cut(bar, cut, 0.1, k_lame, k_density);
    EXPECT_GE(k0.cut_tets, 6u); // at least the six tetrahedra of the cube it crosses
    EXPECT_EQ(zero_modes(k0), 12);
    EXPECT_EQ(zero_modes(k01), 9);
    const PlaneCutSystem whole = assemble_plane_cut(bar, PlaneCut{Eigen::Vector3d::UnitX(), -1.0}, 0.1, k_lame, k_density);
    EXPECT_EQ(whole.cut_tets, 0u);
    EXPECT_EQ(zero_modes(whole), 6);
    // The pieces' masses add up to the bar's.
    Eigen::VectorXd ones_x = Eigen::VectorXd::Zero(static_cast<Eigen::Index>(k0.dofs()));
    for (std::size_t n = 0; n < bar.nodes.size(); ++n) ones_x[static_cast<Eigen::Index>(3 * n)] = 1.0;
    EXPECT_NEAR(ones_x.dot(k0.mass * ones_x), k_density * 0.04 * 0.01 * 0.01, 1e-12);
    for (double r : k0.volume_ratio) {
        EXPECT_GT(r, 0.0);
        EXPECT_LE(r, 1.0);
    }
}
