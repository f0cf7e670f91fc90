// The step's system, assembled from the tetrahedra's gradients row block by row block on all
// threads, against a plain dense assembly of every element's own matrices (XfemElement::stiffness,
// its regions' stiffness, mass) turned by the operator's rotations, on a bar cut once and on one
// cut again lengthwise (tetrahedra cut twice, some where the cuts cross); the rotations against
// the polar factor from an SVD; the forces, products and held dofs likewise.

#include "isxfem/xfem_operator.hpp"

#include "fem/volume_correction.hpp"

#include <Eigen/SVD>

#include <gtest/gtest.h>

#include <random>

using namespace vox;
using namespace vox::isxfem;

namespace {

struct Deformed {
    XfemModel model;
    std::vector<Eigen::Vector3d> x;
    std::vector<unsigned char> fixed;
};

/// A 4 x 2 x 2 bar cut across (and with `twice` lengthwise too), turned by 0.7 rad, stretched and
/// shaken; its enriched blocks open the cuts by a few millimetres; the nodes at x = 0 held.
Deformed deformed_bar(bool twice = false)
{
    TetMesh bar = cube_lattice({4, 2, 2}, 0.01);
    const std::size_t tets = bar.tets.size();
    Deformed d{XfemModel(std::move(bar), {grid::ElasticMaterial{grid::lame_from_young_poisson(1e6, 0.3), 1000.0}},
                         std::vector<std::uint32_t>(tets, 0), 0.1),
               {},
               {}};
    d.model.cut(PlaneCut{Eigen::Vector3d(1.0, 0.2, 0.1).normalized(), 0.021});
    if (twice) {
        const CutReport r = d.model.cut(PlaneCut{Eigen::Vector3d(0.1, 1.0, 0.2).normalized(), 0.0105});
        EXPECT_GT(r.recut_tets, 0u);
        EXPECT_GT(r.crossed_tets, 0u);
    }
    std::mt19937 random(7);
    std::uniform_real_distribution<double> shake(-1e-3, 1e-3);
    const Eigen::Matrix3d turn = Eigen::AngleAxisd(0.7, Eigen::Vector3d(1, 2, 3).normalized()).toRotationMatrix();
    for (std::size_t b = 0; b < d.model.block_count(); ++b) {
        const Eigen::Vector3d noise(shake(random), shake(random), shake(random));
        if (b < d.model.node_count()) {
            const Eigen::Vector3d& rest = d.model.mesh().nodes[b];
            d.x.push_back(turn * Eigen::Vector3d(1.1 * rest.x(), rest.y(), 0.95 * rest.z()) + noise);
        } else {
            d.x.push_back(3.0 * noise);
        }
    }
    d.fixed.assign(3 * d.model.block_count(), 0);
    for (std::size_t n = 0; n < d.model.node_count(); ++n)
        if (d.model.mesh().nodes[n].x() < 1e-9) d.fixed[3 * n] = d.fixed[3 * n + 1] = d.fixed[3 * n + 2] = 1;
    return d;
}

} // namespace

TEST(XfemOperator, MatchesADenseAssemblyOfTheElementMatrices)
{
    for (const bool twice : {false, true}) {
        SCOPED_TRACE(twice ? "cut twice" : "cut once");
        Deformed d = deformed_bar(twice);
        const XfemModel& model = d.model;
        ASSERT_GT(model.block_count(), model.node_count());
        XfemOperator op(model);
        const double scale_m = 1.05, scale_k = 1.2e-4;
        op.update(d.x, d.fixed, scale_m, scale_k);
        const Eigen::MatrixXd first(op.matrix());
        const Eigen::VectorXd first_force = op.internal_force();
        op.update(d.x, d.fixed, scale_m, scale_k); // a second, warm-started update changes nothing
        EXPECT_LT((Eigen::MatrixXd(op.matrix()) - first).cwiseAbs().maxCoeff(), 1e-12 * first.cwiseAbs().maxCoeff());
        EXPECT_LT((op.internal_force() - first_force).norm(), 1e-10 * first_force.norm());

        const auto n = static_cast<Eigen::Index>(3 * model.block_count());
        Eigen::MatrixXd a = Eigen::MatrixXd::Zero(n, n), mass = Eigen::MatrixXd::Zero(n, n);
        Eigen::VectorXd force = Eigen::VectorXd::Zero(n);
        int whole = 0, squeezed = 0;
        for (std::size_t e = 0; e < model.elements().size(); ++e) {
            const XfemElement& el = model.elements()[e];
            const auto blocks = static_cast<Eigen::Index>(el.block_count());
            for (std::size_t region = 0; region < std::max<std::size_t>(el.regions.size(), 1); ++region) {
                const unsigned pattern = el.is_cut() ? el.regions[region].pattern : 0u;
                const Eigen::Matrix3d r = op.rotation(e)[pattern].toRotationMatrix();
                const Eigen::MatrixXd k = el.is_cut() ? el.regions[region].stiffness : Eigen::MatrixXd(el.stiffness);
                Eigen::VectorXd u(3 * blocks);
                for (Eigen::Index i = 0; i < blocks; ++i) {
                    const auto b = el.block(static_cast<std::size_t>(i));
                    u.segment<3>(3 * i) =
                        i < 4 ? Eigen::Vector3d(r.transpose() * d.x[b] - model.mesh().nodes[b]) : Eigen::Vector3d(r.transpose() * d.x[b]);
                }
                const Eigen::VectorXd local = k * u;
                for (Eigen::Index i = 0; i < blocks; ++i) {
                    const auto bi = 3 * static_cast<Eigen::Index>(el.block(static_cast<std::size_t>(i)));
                    force.segment<3>(bi) += r * local.segment<3>(3 * i);
                    for (Eigen::Index j = 0; j < blocks; ++j) {
                        const auto bj = 3 * static_cast<Eigen::Index>(el.block(static_cast<std::size_t>(j)));
                        a.block<3, 3>(bi, bj) += scale_k * r * k.block<3, 3>(3 * i, 3 * j) * r.transpose();
                        if (region == 0) mass.block<3, 3>(bi, bj) += el.mass.block<3, 3>(3 * i, 3 * j);
                    }
                }
            }
            if (!el.is_cut()) { // and the volume correction of a squeezed whole element (fem/volume_correction.hpp)
                const Eigen::Matrix3d r = op.rotation(e)[0].toRotationMatrix();
                Eigen::Matrix3d dx, dX;
                for (int c = 0; c < 3; ++c) {
                    dx.col(c) = d.x[el.node[static_cast<std::size_t>(c + 1)]] - d.x[el.node[0]];
                    dX.col(c) = model.mesh().nodes[el.node[static_cast<std::size_t>(c + 1)]] - model.mesh().nodes[el.node[0]];
                }
                const double lambda_v = el.geometry.volume * model.materials()[el.material].lame.lambda;
                const fem::VolumeCorrection v = fem::volume_correction(dx * dX.inverse(), r, lambda_v);
                squeezed += v.hessian.active();
                for (Eigen::Index i = 0; i < 4; ++i) {
                    const auto bi = 3 * static_cast<Eigen::Index>(el.node[static_cast<std::size_t>(i)]);
                    force.segment<3>(bi) += v.gradient * el.geometry.gradient.row(i).transpose();
                    for (Eigen::Index j = 0; j < 4; ++j)
                        a.block<3, 3>(bi, 3 * static_cast<Eigen::Index>(el.node[static_cast<std::size_t>(j)])) +=
                            scale_k * v.hessian.block(el.geometry.gradient.row(i).transpose(), el.geometry.gradient.row(j).transpose());
                }
            }
            if (!el.is_cut() && whole++ < 20) { // the rotation is the polar factor of F
                Eigen::Matrix3d dx, dX;
                for (int c = 0; c < 3; ++c) {
                    dx.col(c) = d.x[el.node[static_cast<std::size_t>(c + 1)]] - d.x[el.node[0]];
                    dX.col(c) = model.mesh().nodes[el.node[static_cast<std::size_t>(c + 1)]] - model.mesh().nodes[el.node[0]];
                }
                const Eigen::JacobiSVD<Eigen::Matrix3d> svd(dx * dX.inverse(), Eigen::ComputeFullU | Eigen::ComputeFullV);
                EXPECT_LT((op.rotation(e)[0].toRotationMatrix() - svd.matrixU() * svd.matrixV().transpose()).norm(), 1e-11);
            }
        }
        EXPECT_GT(squeezed, 0) << "the bar is deformed enough to squeeze some tetrahedra";
        a += scale_m * mass;
        for (Eigen::Index i = 0; i < n; ++i)
            if (d.fixed[static_cast<std::size_t>(i)]) {
                a.row(i).setZero();
                a.col(i).setZero();
                a(i, i) = 1.0;
            }
        const Eigen::MatrixXd assembled(op.matrix());
        EXPECT_LT((assembled - a).cwiseAbs().maxCoeff(), 1e-12 * a.cwiseAbs().maxCoeff());
        EXPECT_LT((op.internal_force() - force).norm(), 1e-10 * force.norm());
        EXPECT_LT((op.diagonal() - a.diagonal()).norm(), 1e-12 * a.diagonal().norm());
        const Eigen::VectorXd p = Eigen::VectorXd::Random(n);
        Eigen::VectorXd ap, mp;
        op.multiply(p, ap);
        op.mass_multiply(p, mp);
        EXPECT_LT((ap - a * p).norm(), 1e-12 * (a * p).norm());
        EXPECT_LT((mp - mass * p).norm(), 1e-12 * (mass * p).norm());

        // The regularisation adds the same to the free diagonal entries of the blocks it is given.
        const auto jump = static_cast<std::uint32_t>(model.node_count());
        const Eigen::VectorXd before = op.diagonal();
        const double shift = op.add_to_diagonal({jump}, 1e-3);
        double mean = 0.0;
        int count = 0;
        for (Eigen::Index i = 0; i < static_cast<Eigen::Index>(3 * model.node_count()); ++i)
            if (!d.fixed[static_cast<std::size_t>(i)]) {
                mean += before[i];
                ++count;
            }
        EXPECT_NEAR(shift, 1e-3 * mean / count, 1e-12 * shift);
        const Eigen::VectorXd added = op.diagonal() - before;
        for (Eigen::Index i = 0; i < n; ++i)
            EXPECT_NEAR(added[i], i / 3 == jump && !d.fixed[static_cast<std::size_t>(i)] ? shift : 0.0, 1e-12 * before.cwiseAbs().maxCoeff()) << i;
    }
}

TEST(XfemOperator, AtRestHasNoForceAndTheRotationsStayIdentity)
{
    TetMesh bar = cube_lattice({3, 1, 1}, 0.01);
    const std::size_t tets = bar.tets.size();
    XfemModel model(std::move(bar), {grid::ElasticMaterial{grid::lame_from_young_poisson(1e6, 0.3), 1000.0}}, std::vector<std::uint32_t>(tets, 0), 0.1);
    model.cut(PlaneCut{Eigen::Vector3d::UnitX(), 0.013});
    XfemOperator op(model);
    std::vector<Eigen::Vector3d> x = model.mesh().nodes;
    x.resize(model.block_count(), Eigen::Vector3d::Zero());
    op.update(x, std::vector<unsigned char>(3 * x.size(), 0), 1.0, 1e-4);
    EXPECT_EQ(op.internal_force().cwiseAbs().maxCoeff(), 0.0);
    for (std::size_t e = 0; e < model.elements().size(); ++e)
        for (int side : {0, 1}) EXPECT_EQ(op.rotation(e)[static_cast<std::size_t>(side)].w(), 1.0);
}
