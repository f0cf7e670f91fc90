// Haptic subdivision at the contact: the patch's spring layer has the compliance it was scaled to
// at every level; a static press gives the same force for the same displacement before and after
// subdivision, and as the series of the contact and the FEM's compliance predicts; the force does
// not step when the patch moves with a sliding tool or is refined.

#include "contact/contact_patch.hpp"
#include "haptics/coupled_tool.hpp"
#include "surface_snapshots.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>

using namespace vox;

namespace {

constexpr double k_margin = 0.5, k_stiffness = 5.0; // N/mm per cm^2
constexpr double k_compliance = 2.0;                  // mm/N, the FEM's (a soft organ)

/// A 6 x 6 mm flat punch (4 mm tall) whose pushing shape reaches `depth` mm into the wall z = 0
/// at (x, y).
contact::PlacedShape punch_at(const contact::ToolShape& punch, double x, double y, double depth)
{
    contact::PlacedShape p;
    p.shape = &punch;
    p.position = Eigen::Vector3d(x, y, 2.0 + k_margin - depth);
    return p;
}

haptics::DeviceState device_at(const Eigen::Vector3d& p, double t)
{
    haptics::DeviceState d;
    d.position_mm = p;
    d.t_s = t;
    return d;
}

contact::SurfacePoints wall_with_patch(const contact::PlacedShape& tool, int levels)
{
    contact::SurfacePoints s = test::flat_wall(41, true);
    s.index();
    contact::PatchSettings settings;
    settings.levels = levels;
    settings.reach_mm = 3.0; // two levels within the layer's capacity
    settings.max_points = 4000;
    EXPECT_TRUE(contact::build_patch(s, tool, {k_margin, k_stiffness}, k_compliance, settings));
    return s;
}

/// The force felt once the device has held `device` long enough for the proxy and layer to settle.
struct Settled {
    Eigen::Vector3d force, proxy;
};
Settled press(const contact::ToolShape& punch, const contact::SurfacePoints& surface, const Eigen::Vector3d& start, const Eigen::Vector3d& device)
{
    haptics::CoupledTool tool(punch, {k_margin, k_stiffness}, {0.5, 0.0}, surface.capacity());
    tool.update(device_at(start, 0.0), surface, 1e-3);
    Eigen::Vector3d f;
    for (int tick = 1; tick <= 4000; ++tick) f = tool.update(device_at(device, tick * 1e-3), surface, 1e-3);
    return {f, tool.proxy().position};
}

} // namespace

TEST(ContactPatch, ItsLayerHasTheComplianceItWasScaledToAtEveryLevel)
{
    const contact::ToolShape punch = contact::ToolShape::box({6, 6, 4});
    for (int levels : {0, 1, 2}) {
        const contact::SurfacePoints s = wall_with_patch(punch_at(punch, 0.3, -0.2, 0.2), levels);
        const contact::PatchLayer& p = s.patch;
        EXPECT_EQ(p.level, levels);
        EXPECT_NEAR(contact::patch_compliance(p, p.preload_n), k_compliance, 1e-6 * k_compliance);
        // The snapshot points it stands in for are its own free points at level 0.
        std::size_t replaced = 0, carried = 0;
        for (std::size_t i = 0; i < s.count; ++i) replaced += s.is_replaced(i);
        for (std::int32_t v : p.snapshot_point) carried += v >= 0;
        EXPECT_EQ(replaced, carried);
        EXPECT_GT(replaced, 30u);
        // Each level has four times the triangles, and the same area.
        double area = 0.0;
        for (const Eigen::Vector3i& t : p.triangles)
            area += 0.5 * (p.positions_mm[static_cast<std::size_t>(t[1])] - p.positions_mm[static_cast<std::size_t>(t[0])])
                              .cross(p.positions_mm[static_cast<std::size_t>(t[2])] - p.positions_mm[static_cast<std::size_t>(t[0])])
                              .norm();
        EXPECT_NEAR(area, static_cast<double>(p.triangles.size()) / std::pow(4.0, levels) * 0.5, 1e-9) << levels;
    }
}

TEST(ContactPatch, AStaticPressGivesTheSameForceBeforeAndAfterSubdivision)
{
    // The punch touches the wall 0.2 mm deep where the snapshot was taken (the FEM holds that
    // load), then the device presses 2 mm further. Without a patch the snapshot is rigid; with
    // one, the contact is in series with the FEM's compliance, at every level alike.
    const contact::ToolShape punch = contact::ToolShape::box({6, 6, 4});
    const contact::PlacedShape touching = punch_at(punch, 0.3, -0.2, 0.2);
    const Eigen::Vector3d pressed = touching.position - Eigen::Vector3d(0, 0, 2.0);
    contact::SurfacePoints rigid = test::flat_wall(41, true);
    rigid.index();
    const Settled without = press(punch, rigid, touching.position, pressed);
    const double preload = contact::penalty_totals(touching, {k_margin, k_stiffness}, rigid).force_on_tool_n.z();
    std::vector<Settled> with;
    for (int levels : {0, 1, 2}) with.push_back(press(punch, wall_with_patch(touching, levels), touching.position, pressed));
    std::printf("static press, 2 mm past touching: rigid snapshot %.4f N; patch at levels 0, 1, 2: %.4f, %.4f, %.4f N (proxy %.4f, %.4f, %.4f mm)\n",
                without.force.z(), with[0].force.z(), with[1].force.z(), with[2].force.z(), with[0].proxy.z(), with[1].proxy.z(), with[2].proxy.z());
    for (std::size_t k = 1; k < with.size(); ++k) {
        EXPECT_NEAR(with[k].force.z(), with[0].force.z(), 0.01 * with[0].force.z()) << "level " << k;
        EXPECT_NEAR(with[k].proxy.z(), with[0].proxy.z(), 0.01 * (touching.position.z() - with[0].proxy.z())) << "level " << k;
    }
    // The series of contact and layer: the load added is the proxy's move over 1/K + c (K the
    // contact's stiffness over the punch's face), within what the layer's uneven give under a
    // flat face leaves: a rigid punch loads its rim more than the contact's first, even load the
    // layer was scaled under, and is a little stiffer than that load (as on an elastic half-space).
    const double contact_k = k_stiffness / 100.0 * 36.0; // N/mm: 36 mm^2 of face
    for (const Settled& s : with) {
        const double moved = touching.position.z() - s.proxy.z(), added = s.force.z() - preload;
        EXPECT_NEAR(added, moved / (1.0 / contact_k + k_compliance), 0.15 * added);
    }
    // Softer than the rigid snapshot: the surface gives.
    EXPECT_LT(with[1].force.z(), 0.8 * without.force.z());
}

TEST(ContactPatch, TheForceDoesNotStepWhenThePatchMovesOrRefines)
{
    // The punch slides 10 mm at 10 mm/s pressing 1 mm into the patch; a snapshot every 10 ticks,
    // taking up the patch's displacement as the FEM would (its points moved by what the patch
    // hands back) and building the patch anew around the contact, alternately at one and two
    // levels. The force felt changes smoothly.
    const contact::ToolShape punch = contact::ToolShape::box({6, 6, 4});
    contact::PlacedShape tool = punch_at(punch, -5.0, 0.0, 0.2);
    contact::SurfacePoints surface = test::flat_wall(41, true);
    surface.index();
    contact::PatchSettings settings;
    settings.reach_mm = 3.0;
    settings.max_points = 4000;
    ASSERT_TRUE(contact::build_patch(surface, tool, {k_margin, k_stiffness}, k_compliance, settings));
    haptics::CoupledTool coupled(punch, {k_margin, k_stiffness}, {0.5, 0.0}, surface.capacity());
    const Eigen::Vector3d down(0, 0, -1.0);
    coupled.update(device_at(tool.position, 0.0), surface, 1e-3);
    Eigen::Vector3d previous = Eigen::Vector3d::Zero();
    double largest_step = 0.0, largest_force = 0.0;
    int refined = 0;
    for (int tick = 1; tick <= 1200; ++tick) {
        const double t = tick * 1e-3;
        const Eigen::Vector3d device = tool.position + down * std::min(1.0, t / 0.1) + Eigen::Vector3d(10.0 * std::max(0.0, t - 0.15), 0, 0);
        const Eigen::Vector3d f = coupled.update(device_at(device, t), surface, 1e-3);
        if (tick > 200) largest_step = std::max(largest_step, (f - previous).norm()); // after the press
        largest_force = std::max(largest_force, f.norm());
        previous = f;
        if (tick % 10 != 0) continue;
        // The next snapshot: the points the patch stood in for moved as it hands back.
        const contact::PatchLayer& p = surface.patch;
        const std::span<const double> u = coupled.patch().displacement();
        contact::SurfacePoints next = surface;
        for (std::size_t i = 0; i < p.free && i < u.size(); ++i)
            if (p.snapshot_point[i] >= 0) next.positions_mm[static_cast<std::size_t>(p.snapshot_point[i])] -= u[i] * p.normals[i];
        next.t_s = t;
        next.index();
        settings.levels = 1 + (tick / 10) % 2;
        ASSERT_TRUE(contact::build_patch(next, coupled.handed_pose(), {k_margin, k_stiffness}, k_compliance, settings))
            << "tick " << tick << ", proxy " << coupled.proxy().position.transpose();
        refined += next.patch.level != p.level;
        surface = std::move(next);
    }
    std::printf("sliding 10 mm, a new patch every 10 ticks (%d refined or coarsened): largest force %.4f N, largest change in a tick %.5f N\n",
                refined, largest_force, largest_step);
    EXPECT_GT(largest_force, 0.3);
    EXPECT_GT(refined, 50);
    EXPECT_LT(largest_step, 0.01) << "largest force " << largest_force;
}

TEST(ContactPatch, ANewPatchOnALaggingSnapshotCarriesTheForceOnAndHandsItOver)
{
    // The punch pressed 1 mm into a patch and settled. The simulation is handed the tool backed
    // out by the layer's give. The next snapshot has not moved at all (a FEM that has not yet
    // taken up any of the give): the new patch, built where the simulation has the tool, starts
    // from the last patch's load, not from the rigid snapshot's (larger) one, and its carried load
    // fades over ContactPatchState::k_handoff_s into the new patch's own settled force.
    const contact::ToolShape punch = contact::ToolShape::box({6, 6, 4});
    const contact::PlacedShape touching = punch_at(punch, 0.3, -0.2, 0.2);
    const Eigen::Vector3d device = touching.position - Eigen::Vector3d(0, 0, 1.0);
    const contact::SurfacePoints first = wall_with_patch(touching, 1);
    haptics::CoupledTool tool(punch, {k_margin, k_stiffness}, {0.5, 0.0}, first.capacity());
    tool.update(device_at(touching.position, 0.0), first, 1e-3);
    Eigen::Vector3d settled;
    for (int tick = 1; tick <= 4000; ++tick) settled = tool.update(device_at(device, tick * 1e-3), first, 1e-3);
    const double give = tool.patch().give_mm();
    ASSERT_GT(give, 0.05);
    const contact::PlacedShape handed = tool.handed_pose();
    EXPECT_NEAR((handed.position - tool.proxy().position).z(), give, 1e-9); // backed out along the contact's force, +z
    EXPECT_NEAR((handed.position - tool.proxy().position).head<2>().norm(), 0.0, 1e-6);

    contact::SurfacePoints next = wall_with_patch(handed, 1);
    next.t_s = first.t_s + 0.01;
    contact::SurfacePoints wall = test::flat_wall(41, true);
    wall.index();
    const Eigen::Vector3d rigid = contact::penalty_totals(tool.proxy(), {k_margin, k_stiffness}, wall).force_on_tool_n; // a restart from rest
    Eigen::Vector3d previous = settled, f;
    double largest_step = 0.0;
    for (int tick = 1; tick <= 300; ++tick) {
        f = tool.update(device_at(device, 4.0 + tick * 1e-3), next, 1e-3);
        largest_step = std::max(largest_step, (f - previous).norm());
        previous = f;
    }
    const Settled own = press(punch, next, handed.position, device);
    std::printf("handoff: settled %.4f N (give %.4f mm); on the lagging snapshot a rigid restart %.4f N, the largest change in a tick %.5f N, "
                "after 0.3 s %.4f N (the new patch settled alone: %.4f N)\n",
                settled.z(), give, rigid.z(), largest_step, f.z(), own.force.z());
    EXPECT_GT(rigid.z() - settled.z(), 0.05) << "the lagging snapshot would step the force";
    EXPECT_LT(largest_step, 0.01);
    EXPECT_NEAR(f.z(), own.force.z(), 0.01 * own.force.z());
}

TEST(ContactPatch, AStiffBallPressedDeepIntoASoftLayerSettlesWithoutRinging)
{
    // A finger-sized ball with a stiff contact (20 N/mm per cm^2) pressed 4 mm past touching into
    // a patch as soft as a scalp (4.5 mm/N): the proxy's step, taken on the contact's own
    // stiffness, approaches the layer's equilibrium from one side. (Taken on the contact in series
    // with the layer, a soft stiffness the layer only has once settled, it overshot: here by
    // 0.05 N a tick; on skull_scalp_press.json at level 2 the force rang between the clamp's two
    // signs.) The force rises and settles smoothly.
    const contact::ToolShape ball = contact::ToolShape::sphere(8.0);
    const contact::ContactParameters contact{1.0, 20.0};
    contact::PlacedShape tool;
    tool.shape = &ball;
    tool.position = Eigen::Vector3d(0, 0, 8.0 + 1.0 - 0.5); // its pushing shape 0.5 mm into the wall
    contact::SurfacePoints surface = test::flat_wall(41, true);
    surface.index();
    ASSERT_TRUE(contact::build_patch(surface, tool, contact, 4.5));
    haptics::CoupledTool coupled(ball, contact, {0.5, 0.0}, surface.capacity());
    const Eigen::Vector3d start = tool.position + Eigen::Vector3d(0, 0, 1.0); // clear of the wall by 0.5 mm
    Eigen::Vector3d previous = coupled.update(device_at(start, 0.0), surface, 1e-3);
    double largest_step = 0.0, largest_force = 0.0;
    Eigen::Vector3d f = previous;
    for (int tick = 1; tick <= 600; ++tick) {
        const double t = tick * 1e-3;
        const Eigen::Vector3d device = start - Eigen::Vector3d(0, 0, 4.5 * std::min(1.0, t / 0.25));
        f = coupled.update(device_at(device, t), surface, 1e-3);
        largest_step = std::max(largest_step, (f - previous).norm());
        largest_force = std::max(largest_force, f.norm());
        previous = f;
    }
    std::printf("stiff ball 4 mm into a soft layer: settled %.4f N, largest %.4f N, largest change in a tick %.5f N\n", f.norm(), largest_force,
                largest_step);
    EXPECT_GT(f.z(), 0.5);
    EXPECT_LT(largest_force, 1.05 * f.norm());
    EXPECT_LT(largest_step, 0.03);
}
