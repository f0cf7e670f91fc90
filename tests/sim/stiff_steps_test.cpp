// Stiff and extreme cases stay cheap and never stop a session: a stiff loose piece falls without
// substeps (gravity acts on the whole lumped mass, so a free piece does not bend by itself), and
// a 100 N kick that the linearised step cannot take is solved by the nonlinear step.

#include "grid/label_grid.hpp"
#include "io/scene.hpp"
#include "io/scene_object.hpp"
#include "sim/frame_loop.hpp"
#include "sim/run_record.hpp"
#include "sim/method_factory.hpp"
#include "sim/tool_policy.hpp"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <filesystem>

namespace fs = std::filesystem;

namespace vox::sim {
namespace {

std::vector<FrameStats> run(const io::Scene& scene, int frames)
{
    auto labels = std::make_shared<const grid::LabelGrid>(io::load_scene_object(scene));
    auto method = open_method(scene, labels).method;
    ToolPolicy tools(scene);
    FrameLoop loop(scene, *method, tools);
    std::vector<FrameStats> out;
    for (int f = 0; f < frames; ++f) out.push_back(loop.next());
    return out;
}

TEST(StiffSteps, AStiffLoosePieceInACornerOfItsElementFallsWithoutSubsteps)
{
    // 2 x 2 x 2 voxels in a corner of a level-3 cell: the cell's far corners carry almost no
    // material, so they get the mass floor.
    const fs::path path = fs::path(::testing::TempDir()) / "corner_piece.vdb";
    grid::LabelGrid g;
    for (int k = 0; k < 2; ++k)
        for (int j = 0; j < 2; ++j)
            for (int i = 0; i < 2; ++i) g.set({i, j, k}, 1);
    g.save(path);
    const nlohmann::json doc = {
        {"object", {{"volume", path.string()}, {"levels", 3}, {"unheld_pieces", "fall"}}},
        {"materials", {{"default", {{"youngs_modulus_pa", 1e9}, {"poisson_ratio", 0.3}, {"density_kg_m3", 1900}}}}},
        {"solver", {{"dt_s", 0.01}}},
        {"gravity_m_s2", {0, 0, -9.81}},
    };
    const std::vector<FrameStats> frames = run(io::parse_scene(doc, ::testing::TempDir(), "corner.json"), 30);
    for (const FrameStats& f : frames) {
        EXPECT_EQ(f.step.substeps, 0) << "frame " << f.frame;
        ASSERT_TRUE(f.step.elastic_energy_j.has_value());
        EXPECT_LT(*f.step.elastic_energy_j, 1e-9 * f.step.kinetic_energy_j + 1e-18) << "frame " << f.frame << ": it bent while falling";
    }
    EXPECT_GT(frames.back().step.max_displacement_mm, 30.0) << "it fell";
}

TEST(StiffSteps, AHundredNewtonKickIsSolvedByTheNonlinearStep)
{
    // A 40 mm soft beam held at one end, 100 N on its free end for one step (the stability
    // bench's case, which once stopped the run).
    const nlohmann::json doc = {
        {"object", {{"phantom", {{"shape", "beam"}, {"size_mm", {40, 10, 10}}}}, {"levels", 1}}},
        {"materials", {{"default", {{"youngs_modulus_pa", 3e4}, {"poisson_ratio", 0.45}, {"density_kg_m3", 1000}}}}},
        {"solver", {{"dt_s", 0.01}, {"cg_max_iterations", 300}}},
        {"gravity_m_s2", {0, 0, -9.81}},
        {"constraints", {{{"type", "fixed"}, {"box_mm", {{-1e3, -1e3, -1e3}, {0, 1e3, 1e3}}}}}},
        {"loads", {{{"box_mm", {{37.5, -1e3, -1e3}, {1e3, 1e3, 1e3}}}, {"force_n", {0, 0, -100}}}}},
    };
    const io::Scene scene = io::parse_scene(doc, ::testing::TempDir(), "kick.json");
    auto labels = std::make_shared<const grid::LabelGrid>(io::load_scene_object(scene));
    auto method = open_method(scene, labels).method;
    ToolPolicy tools(scene);
    FrameLoop loop(scene, *method, tools);
    const FrameStats kick = loop.next();
    EXPECT_GT(kick.step.newton_iterations, 0) << "the linearised step created energy: the nonlinear step took over";
    EXPECT_FALSE(kick.step.energy_projected);
    EXPECT_TRUE(std::isfinite(kick.step.max_displacement_mm));
    // Said as it is: a flung beam's Newton step stops at its cap far from converged (its energy
    // is physical, so it is kept); that is a step that did not converge, not one that recovered.
    EXPECT_EQ(kick.step.recovered, kick.step.converged);
    EXPECT_TRUE(kick.step.preconditioner_fallback.empty());
    RunRecord record(scene.source, *method, scene.solver.dt_s);
    record.add(kick, *method);
    const FrameStats next = loop.next();
    record.add(next, *method);
    record.finish(*method);
    const nlohmann::json& summary = record.document()["summary"];
    EXPECT_EQ(summary["nonconverged_steps"], int(!kick.step.converged) + int(!next.step.converged));
    EXPECT_EQ(summary["recovered_steps"], int(kick.step.recovered) + int(next.step.recovered));
    EXPECT_EQ(summary["preconditioner_fallbacks"], 0);
    EXPECT_EQ(record.document()["frames"][0]["recovered"], kick.step.recovered);
}

} // namespace
} // namespace vox::sim
