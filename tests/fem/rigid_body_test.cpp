// The rigid body's step: a free spin about a principal axis keeps its rate and the body's shape;
// a stiff penalty contact on a light body, which an explicit step would blow up at this dt,
// settles where the spring balances gravity; the fitted state of rigidly placed nodes is exact.

#include "fem/rigid_body.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>

namespace vox::fem {
namespace {

/// The 8 corners of a 10 x 20 x 30 mm box, 1 g each.
struct Box {
    std::vector<Eigen::Vector3d> x, v;
    std::vector<double> mass = std::vector<double>(8, 1e-3);
    std::vector<std::uint32_t> nodes{0, 1, 2, 3, 4, 5, 6, 7};
    Box()
    {
        for (int c = 0; c < 8; ++c) x.emplace_back(0.01 * (c & 1), 0.02 * ((c >> 1) & 1), 0.03 * ((c >> 2) & 1));
        v.assign(8, Eigen::Vector3d::Zero());
    }
};

TEST(RigidBody, FitsTheStateOfRigidlyMovingNodesExactly)
{
    Box b;
    const RigidBody body(b.nodes, b.x, b.mass);
    const Eigen::Matrix3d r = Eigen::AngleAxisd(0.7, Eigen::Vector3d(1, 2, 3).normalized()).toRotationMatrix();
    const Eigen::Vector3d centre(0.005, 0.01, 0.015), shift(0.1, -0.2, 0.3), vel(1, 2, 3), spin(-4, 5, 6);
    std::vector<Eigen::Vector3d> x(8), v(8);
    for (int c = 0; c < 8; ++c) {
        const Eigen::Vector3d arm = r * (b.x[static_cast<std::size_t>(c)] - centre);
        x[static_cast<std::size_t>(c)] = centre + shift + arm;
        v[static_cast<std::size_t>(c)] = vel + spin.cross(arm);
    }
    const RigidBody::State s = body.state(x, v);
    EXPECT_LT((s.centre - centre - shift).norm(), 1e-12);
    EXPECT_LT((s.rotation - r).norm(), 1e-12);
    EXPECT_LT((s.velocity - vel).norm(), 1e-12);
    EXPECT_LT((s.angular_velocity - spin).norm(), 1e-9);
}

TEST(RigidBody, SpinsFreelyAboutAPrincipalAxisKeepingItsRateAndShape)
{
    Box b;
    const RigidBody body(b.nodes, b.x, b.mass);
    const Eigen::Vector3d centre(0.005, 0.01, 0.015);
    const double rate = 2.0 * std::numbers::pi; // 1 turn a second about z
    for (int c = 0; c < 8; ++c) b.v[static_cast<std::size_t>(c)] = Eigen::Vector3d(0, 0, rate).cross(b.x[static_cast<std::size_t>(c)] - centre);
    const std::vector<Eigen::Vector3d> none(8, Eigen::Vector3d::Zero());
    const std::vector<std::int32_t> body_of(8, 0);
    const double dt = 0.01;
    for (int k = 0; k < 25; ++k) body.advance(body.state(b.x, b.v), dt, 0.0, Eigen::Vector3d::Zero(), none, {}, body_of, 0, b.x, b.v);
    const RigidBody::State s = body.state(b.x, b.v);
    EXPECT_NEAR(s.angular_velocity.z(), rate, 1e-9);
    EXPECT_LT(s.angular_velocity.head<2>().norm(), 1e-9);
    EXPECT_LT((s.centre - centre).norm(), 1e-12);
    // A quarter turn after 0.25 s: the box's x edge now points along y.
    EXPECT_NEAR((s.rotation * Eigen::Vector3d::UnitX()).y(), 1.0, 1e-9);
    EXPECT_NEAR((b.x[1] - b.x[0]).norm(), 0.01, 1e-12);
}

TEST(RigidBody, RestsOnAStiffContactThatAnExplicitStepWouldBlowUp)
{
    // 8 g on one penalty spring of 1e5 N/m under its lowest corner: sqrt(m / k) = 2.8e-4 s, far
    // below dt = 0.01 s. The implicit step settles where k d = m g (with damping of the tilt).
    Box b;
    const RigidBody body(b.nodes, b.x, b.mass);
    const std::vector<Eigen::Vector3d> none(8, Eigen::Vector3d::Zero());
    const std::vector<std::int32_t> body_of(8, 0);
    const Eigen::Vector3d g(0, 0, -9.81);
    const double k = 1e5, dt = 0.01;
    std::vector<Eigen::Vector3d> support(8);
    for (int c = 0; c < 8; ++c) support[static_cast<std::size_t>(c)] = b.x[static_cast<std::size_t>(c)];
    for (int step = 0; step < 300; ++step) {
        // Springs under the four bottom corners (z = 0), pushing up only where they are pressed.
        std::vector<NodeContact> contact;
        for (std::uint32_t c = 0; c < 4; ++c) {
            const double depth = support[c].z() - b.x[c].z();
            if (depth <= 0.0) continue;
            NodeContact n;
            n.node = c;
            n.force_n = Eigen::Vector3d(0, 0, k * depth);
            n.stiffness_n_per_m(2, 2) = k;
            contact.push_back(n);
        }
        body.advance(body.state(b.x, b.v), dt, 5.0, g, none, contact, body_of, 0, b.x, b.v);
        for (const Eigen::Vector3d& p : b.x) ASSERT_TRUE(p.allFinite());
    }
    const RigidBody::State s = body.state(b.x, b.v);
    EXPECT_LT(s.velocity.norm(), 1e-6);
    const double sink = 0.015 - s.centre.z();
    EXPECT_NEAR(sink, 8e-3 * 9.81 / (4.0 * k), 1e-8); // four springs share the weight
}

} // namespace
} // namespace vox::fem
