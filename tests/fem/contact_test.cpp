// Implicit penalty contact in the solver: at a static equilibrium the contact force at the final
// position, F - K (x - x0), is what holds the block, and the response follows the linear
// compliance u = c F / (1 + K c); a stiff contact on a light node stays bounded at a large dt
// and never creates energy.

#include "fem/implicit_solver.hpp"

#include "fem/block_grid.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <vector>

using namespace vox;
using namespace vox::fem;

namespace {

using test::block_grid;
using test::nodes_at;

/// The node at rest position `mm` (millimetres).
std::uint32_t node_at(const HexModel& model, const Eigen::Vector3d& mm)
{
    for (std::uint32_t n = 0; n < model.node_count(); ++n)
        if ((model.rest_positions()[n] - 1e-3 * mm).norm() < 1e-9) return n;
    ADD_FAILURE() << "no node at " << mm.transpose() << " mm";
    return 0;
}

/// A 4 x 4 x 4 mm block (2 mm elements) held on its bottom face (z = -0.5 mm).
struct HeldBlock {
    grid::BranchedGrid grid = block_grid({4, 4, 4}, 2);
    HexModel model{grid, 1};
    std::uint32_t top = node_at(model, {1.5, 1.5, 3.5}); ///< the middle of the top face

    ImplicitSolver solver(const SolverOptions& o) const
    {
        ImplicitSolver s(model, o);
        for (std::uint32_t n : nodes_at(model, 2, -0.0005)) s.fix(n, 7);
        return s;
    }
};

SolverOptions quasi_static()
{
    SolverOptions o;
    o.quasi_static = true;
    o.cg_tolerance = 1e-9; // the force residual's rounding floor is near 1e-11 of these small loads
    o.cg_max_iterations = 5000;
    o.newton_max_iterations = 50;
    return o;
}

NodeContact contact_along_z(std::uint32_t node, double force_n, double stiffness_n_per_m)
{
    NodeContact c;
    c.node = node;
    c.force_n = Eigen::Vector3d(0, 0, force_n);
    c.stiffness_n_per_m(2, 2) = stiffness_n_per_m;
    return c;
}

double max_difference(const std::vector<Eigen::Vector3d>& a, const std::vector<Eigen::Vector3d>& b)
{
    double d = 0.0;
    for (std::size_t n = 0; n < a.size(); ++n) d = std::max(d, (a[n] - b[n]).norm());
    return d;
}

} // namespace

TEST(SolverContact, QuasiStaticEquilibriumIsThePlainForceOfTheFinalContactForce)
{
    const HeldBlock block;
    const double force = -1e-4; // N, a 1 um push on a 2 mm element: linear to about 1e-4
    // The node's compliance along z under a plain force.
    ImplicitSolver plain = block.solver(quasi_static());
    plain.external_forces()[block.top] = {0, 0, force};
    ASSERT_TRUE(plain.step().converged);
    const double c = (plain.positions()[block.top] - block.model.rest_positions()[block.top]).z() / force; // m/N
    ASSERT_GT(c, 0.0);
    // A contact as stiff as the block there: the spring takes half the load.
    for (double stiffness : {0.0, 0.3 / c, 1.0 / c, 10.0 / c}) {
        SCOPED_TRACE(testing::Message() << "K c = " << stiffness * c);
        ImplicitSolver with_contact = block.solver(quasi_static());
        with_contact.set_contact({contact_along_z(block.top, force, stiffness)});
        const StepStats s = with_contact.step();
        ASSERT_TRUE(s.converged);
        const Eigen::Vector3d x0 = block.model.rest_positions()[block.top]; // where the contact was set
        const double u = (with_contact.positions()[block.top] - x0).z();
        // Linear theory: u = c (F - K u).
        EXPECT_NEAR(u, c * force / (1.0 + stiffness * c), 1e-3 * std::abs(c * force));
        // The contact force at the final position, applied as a plain force, holds the block in
        // exactly the same place: the equilibrium is the same one.
        const Eigen::Vector3d final_force = with_contact.contact()[0].force_n -
                                            with_contact.contact()[0].stiffness_n_per_m * (with_contact.positions()[block.top] - x0);
        EXPECT_NEAR(final_force.z(), force - stiffness * u, 1e-15);
        ImplicitSolver same = block.solver(quasi_static());
        same.external_forces()[block.top] = final_force;
        ASSERT_TRUE(same.step().converged);
        EXPECT_LT(max_difference(same.positions(), with_contact.positions()), 1e-7 * std::abs(u));
        // At equilibrium a further frame changes nothing (at most one Newton iteration: the
        // residual is now measured against the smaller final force).
        const std::vector<Eigen::Vector3d> settled = with_contact.positions();
        const StepStats again = with_contact.step();
        EXPECT_TRUE(again.converged);
        EXPECT_LE(again.newton_iterations, 1);
        EXPECT_LT(max_difference(settled, with_contact.positions()), 1e-8 * std::abs(u));
    }
}

TEST(SolverContact, ContactSetWhereTheNodeIsMeasuresDisplacementFromThere)
{
    // Set the contact after a first load moved the node: x0 is that position, so a contact with
    // zero force and any stiffness holds it there (the elastic force there is balanced by the
    // plain force still applied).
    const HeldBlock block;
    ImplicitSolver solver = block.solver(quasi_static());
    solver.external_forces()[block.top] = {0, 0, -1e-4};
    ASSERT_TRUE(solver.step().converged);
    const std::vector<Eigen::Vector3d> before = solver.positions();
    solver.set_contact({contact_along_z(block.top, 0.0, 1e3)});
    const StepStats s = solver.step();
    EXPECT_TRUE(s.converged);
    EXPECT_EQ(s.newton_iterations, 0);
    EXPECT_LT(max_difference(before, solver.positions()), 1e-15);
    // Replacing the contacts forgets the old ones; listing a node twice is refused.
    solver.set_contact({});
    EXPECT_TRUE(solver.contact().empty());
    EXPECT_THROW(solver.set_contact({contact_along_z(block.top, 0, 1), contact_along_z(block.top, 0, 1)}), std::invalid_argument);
}

TEST(SolverContact, StiffContactOnALightNodeStaysBoundedAndDissipates)
{
    // K = 1e6 N/m on a node of a few milligrams: sqrt(K / m) * dt is thousands, where an
    // explicit penalty would explode. Implicit Euler on the contact must keep the total energy
    // kinetic + elastic + K u^2 / 2 - F.u from ever growing; starting at rest with F applied,
    // that energy stays <= 0, which bounds the node's displacement by 2 F / K.
    const HeldBlock block;
    const double stiffness = 1e6, force = -1e-3;
    const double mass = block.model.nodal_mass()[block.top];
    SolverOptions o;
    o.dt_s = 0.01;
    o.cg_tolerance = 1e-12;
    o.cg_max_iterations = 5000;
    ASSERT_GT(std::sqrt(stiffness / mass) * o.dt_s, 1e3);
    ImplicitSolver solver = block.solver(o);
    solver.set_contact({contact_along_z(block.top, force, stiffness)});
    const Eigen::Vector3d x0 = block.model.rest_positions()[block.top];
    auto total_energy = [&](const StepStats& s) {
        const Eigen::Vector3d u = solver.positions()[block.top] - x0;
        return s.kinetic_energy_j + s.elastic_energy_j + 0.5 * stiffness * u.z() * u.z() - force * u.z();
    };
    double previous = 0.0; // at rest, undisplaced
    double largest = 0.0;
    for (int k = 0; k < 100; ++k) {
        const StepStats s = solver.step();
        ASSERT_TRUE(std::isfinite(s.kinetic_energy_j) && std::isfinite(s.elastic_energy_j)) << "step " << k;
        EXPECT_FALSE(s.energy_projected) << "step " << k;
        EXPECT_EQ(s.substeps, 0) << "step " << k; // stable at the full dt, no halving needed
        const double e = total_energy(s);
        EXPECT_LE(e, previous + 1e-12 * std::abs(force * force / stiffness)) << "step " << k;
        previous = e;
        largest = std::max(largest, std::abs((solver.positions()[block.top] - x0).z()));
    }
    EXPECT_LE(largest, 2 * std::abs(force) / stiffness * (1 + 1e-9));
    // It comes to rest at the static equilibrium of the same contact.
    ImplicitSolver statics = block.solver(quasi_static());
    statics.set_contact({contact_along_z(block.top, force, stiffness)});
    ASSERT_TRUE(statics.step().converged);
    const double u_static = (statics.positions()[block.top] - x0).z();
    EXPECT_GT(std::abs(u_static), 0.9 * std::abs(force) / stiffness); // the contact is far stiffer than the block
    EXPECT_LT(max_difference(statics.positions(), solver.positions()), 1e-6 * std::abs(u_static));
}

TEST(SolverContact, StiffContactAbsorbsAKickWithoutGainingEnergy)
{
    // No contact force, only stiffness: a node thrown into it at 0.1 m/s. The energy
    // kinetic + elastic + K u^2 / 2 never grows, so the penetration stays below
    // sqrt(2 E0 / K).
    const HeldBlock block;
    const double stiffness = 1e6;
    SolverOptions o;
    o.dt_s = 0.01;
    o.cg_tolerance = 1e-12;
    o.cg_max_iterations = 5000;
    ImplicitSolver solver = block.solver(o);
    const Eigen::Matrix3d k = stiffness * Eigen::Matrix3d::Identity();
    NodeContact contact;
    contact.node = block.top;
    contact.stiffness_n_per_m = k;
    solver.set_contact({contact});
    solver.velocities()[block.top] = {0.02, -0.03, -0.1};
    const double e0 = 0.5 * block.model.nodal_mass()[block.top] * solver.velocities()[block.top].squaredNorm();
    const Eigen::Vector3d x0 = block.model.rest_positions()[block.top];
    double previous = e0, largest = 0.0;
    for (int k_step = 0; k_step < 50; ++k_step) {
        const StepStats s = solver.step();
        const Eigen::Vector3d u = solver.positions()[block.top] - x0;
        const double e = s.kinetic_energy_j + s.elastic_energy_j + 0.5 * u.dot(k * u);
        ASSERT_TRUE(std::isfinite(e)) << "step " << k_step;
        EXPECT_EQ(s.substeps, 0) << "step " << k_step;
        EXPECT_LE(e, previous * (1 + 1e-9) + 1e-30) << "step " << k_step;
        previous = e;
        largest = std::max(largest, u.norm());
    }
    EXPECT_LE(largest, std::sqrt(2 * e0 / stiffness) * (1 + 1e-9));
    EXPECT_LT(previous, 1e-6 * e0); // implicit Euler at this dt damps it away
}

TEST(Contact, ABadContactListIsRefusedAndChangesNothing)
{
    const HeldBlock b;
    ImplicitSolver s = b.solver(quasi_static());
    s.set_contact({{b.top, {0, 0, -1e-3}, Eigen::Matrix3d::Identity()}});
    const auto out_of_range = static_cast<std::uint32_t>(b.model.node_count());
    const Eigen::Vector3d f0 = Eigen::Vector3d::Zero();
    const Eigen::Matrix3d k0 = Eigen::Matrix3d::Zero();
    EXPECT_THROW(s.set_contact({{b.top, f0, k0}, {out_of_range, f0, k0}}), std::invalid_argument);
    EXPECT_THROW(s.set_contact({{b.top, f0, k0}, {b.top, f0, k0}}), std::invalid_argument);
    ASSERT_EQ(s.contact().size(), 1u); // the earlier contact still holds
    EXPECT_EQ(s.contact()[0].node, b.top);
    s.step(); // and the solver still works with it
    EXPECT_LT(s.positions()[b.top].z(), b.model.rest_positions()[b.top].z());
}
