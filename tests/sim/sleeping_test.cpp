// Pieces at rest sleep: a damped cantilever that has settled under gravity stops being stepped
// (its nodes stay exactly where they settled), a tool coming within reach wakes it and it bends
// under the tool; a loose block falling never sleeps.

#include "io/scene.hpp"
#include "io/scene_object.hpp"
#include "sim/dbg_simulation.hpp"
#include "sim/frame_loop.hpp"
#include "sim/method_factory.hpp"
#include "sim/tool_policy.hpp"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

namespace vox::sim {
namespace {

/// A 40 x 10 x 10 mm beam of 2 mm voxels held at x = 0, heavily damped; a sphere waits far above
/// its tip and comes down onto it from 1.5 s.
io::Scene settling_beam(const char* unheld = "hold")
{
    const nlohmann::json doc = {
        {"object", {{"phantom", {{"shape", "beam"}, {"size_mm", {40, 10, 10}}, {"voxel_mm", 2}}}, {"levels", 1}, {"unheld_pieces", unheld}}},
        {"materials", {{"default", {{"youngs_modulus_pa", 2e5}, {"poisson_ratio", 0.3}, {"density_kg_m3", 1000}}}}},
        {"solver", {{"type", "dbg"}, {"dt_s", 0.01}, {"rayleigh_mass_per_s", 20.0}}},
        {"gravity_m_s2", {0, 0, -9.81}},
        {"constraints", {{{"type", "fixed"}, {"box_mm", {{-1, -1, -1}, {0, 11, 11}}}}}},
        {"tools", {{{"name", "finger"}, {"shape", "sphere"}, {"radius_mm", 3}}}},
        {"script",
         {{{"t_s", 0.0}, {"tool", "finger"}, {"position_mm", {36, 5, 60}}},
          {{"t_s", 1.5}, {"tool", "finger"}, {"position_mm", {36, 5, 60}}},
          {{"t_s", 2.0}, {"tool", "finger"}, {"position_mm", {36, 5, 8}}}}},
    };
    return io::parse_scene(doc, ::testing::TempDir(), "settling_beam.json");
}

TEST(Sleeping, ASettledPieceStopsBeingSteppedUntilAToolComesNear)
{
    const io::Scene scene = settling_beam();
    auto labels = std::make_shared<const grid::LabelGrid>(io::load_scene_object(scene));
    std::unique_ptr<Method> method = open_method(scene, labels).method;
    ToolPolicy tools(scene);
    FrameLoop loop(scene, *method, tools);
    int first_asleep = 0;
    std::vector<Eigen::Vector3d> settled;
    for (int f = 1; f <= 150; ++f) {
        const FrameStats s = loop.next();
        if (s.step.asleep_pieces == 1 && !first_asleep) {
            first_asleep = f;
            settled = method->surface_displacements_mm();
        } else if (first_asleep) {
            EXPECT_EQ(s.step.cg_iterations, 0) << "frame " << f << ": the whole object sleeps, nothing is solved";
        }
    }
    ASSERT_GT(first_asleep, 50) << "it sleeps only after half a second at rest";
    // Asleep: not a node moved since (exactly), while gravity still acts on it.
    const std::vector<Eigen::Vector3d> now = method->surface_displacements_mm();
    ASSERT_EQ(now.size(), settled.size());
    double sag = 0.0;
    for (std::size_t v = 0; v < now.size(); ++v) {
        EXPECT_EQ(now[v], settled[v]) << "vertex " << v;
        sag = std::min(sag, now[v].z());
    }
    EXPECT_LT(sag, -0.05) << "it settled in its sag";
    // The finger comes down onto the tip: the beam wakes and bends further under it.
    int woke = 0;
    for (int f = 151; f <= 200; ++f) {
        const FrameStats s = loop.next();
        if (!woke && s.step.asleep_pieces == 0) woke = f;
    }
    EXPECT_GT(woke, 0) << "the tool woke it";
    double pushed = 0.0;
    for (const Eigen::Vector3d& d : method->surface_displacements_mm()) pushed = std::min(pushed, d.z());
    EXPECT_LT(pushed, sag - 0.1) << "and it bent under the tool";
}

TEST(Sleeping, AFallingPieceNeverSleeps)
{
    // Nothing holds the beam ("fall"): it falls the whole time, so it never sleeps.
    io::Scene scene = settling_beam("fall");
    scene.constraints.clear();
    auto labels = std::make_shared<const grid::LabelGrid>(io::load_scene_object(scene));
    std::unique_ptr<Method> method = open_method(scene, labels).method;
    ToolPolicy tools(scene);
    FrameLoop loop(scene, *method, tools);
    for (int f = 1; f <= 100; ++f) EXPECT_EQ(loop.next().step.asleep_pieces, 0u) << "frame " << f;
}

} // namespace
} // namespace vox::sim
