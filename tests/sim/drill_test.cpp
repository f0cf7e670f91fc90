// The drill: a spinning burr removes what it touches at the rate the scene sets (rate constant x
// pressing force x revolutions per second), nothing when it touches nothing, and a faster burr
// removes more; Is-XFEM refuses it by name.

#include "core/error.hpp"
#include "io/scene.hpp"
#include "io/scene_object.hpp"
#include "sim/frame_loop.hpp"
#include "sim/method_factory.hpp"
#include "sim/tool_policy.hpp"
#include "sim/undo_history.hpp"

#include <gtest/gtest.h>
#include <algorithm>
#include <nlohmann/json.hpp>

namespace vox::sim {
namespace {

/// A 20 mm block of 1 mm voxels held at its base; a burr (`shape`) whose driver is pressed
/// `press_mm` into the middle of its top for 0.3 s, then lifted clear.
io::Scene drilling(const nlohmann::json& burr, const char* solver = "dbg", double press_mm = 1.5)
{
    // The burr's lowest point 1.5 mm below the top face (z = 19.5 mm).
    const double depth_offset = burr.value("shape", "") == "cylinder" ? burr.value("length_mm", 0.0) / 2 : burr.value("radius_mm", 0.0);
    nlohmann::json tool = burr;
    tool["name"] = "burr";
    tool["action"] = "drill";
    const nlohmann::json doc = {
        {"object", {{"phantom", {{"shape", "block"}}}, {"levels", 1}}},
        {"materials", {{"default", {{"youngs_modulus_pa", 1e7}, {"poisson_ratio", 0.3}, {"density_kg_m3", 1900}}}}},
        {"solver", {{"type", solver}, {"dt_s", 0.01}}},
        {"gravity_m_s2", {0, 0, -9.81}},
        {"constraints", {{{"type", "fixed"}, {"box_mm", {{-1, -1, -1}, {20, 20, 0}}}}}},
        {"tools", {tool}},
        {"script",
         {{{"t_s", 0.0}, {"tool", "burr"}, {"position_mm", {9.5, 9.5, 25}}},
          {{"t_s", 0.05}, {"tool", "burr"}, {"position_mm", {9.5, 9.5, 19.5 + depth_offset - press_mm}}},
          {{"t_s", 0.35}, {"tool", "burr"}, {"position_mm", {9.5, 9.5, 19.5 + depth_offset - press_mm}}},
          {{"t_s", 0.4}, {"tool", "burr"}, {"position_mm", {9.5, 9.5, 40}}}}},
    };
    return io::parse_scene(doc, ::testing::TempDir(), "drill.json");
}

struct Drilled {
    std::size_t removed_voxels = 0;
    double allowed_mm3 = 0.0; ///< sum over frames of rate x |force| x rev/s x dt
    std::size_t removed_while_clear = 0;
};

Drilled drill(const io::Scene& scene, int frames)
{
    auto labels = std::make_shared<const grid::LabelGrid>(io::load_scene_object(scene));
    auto method = open_method(scene, labels).method;
    ToolPolicy tools(scene);
    FrameLoop loop(scene, *method, tools);
    const io::ToolSpec& spec = scene.tools[0];
    Drilled out;
    for (int f = 0; f < frames; ++f) {
        const FrameStats s = loop.next();
        out.removed_voxels += s.tools.cut.removed_voxels;
        const ToolFrame& t = s.tools.tools[0];
        const double pressing_n = t.force_n.norm() > 0.0 ? std::max(t.force_n.norm(), t.coupling_force_n.norm()) : 0.0;
        out.allowed_mm3 += spec.drill_rate_mm3_per_n_rev * pressing_n * spec.burr_speed_rpm / 60.0 * scene.solver.dt_s;
        if (t.force_n.norm() == 0.0) out.removed_while_clear += s.tools.cut.removed_voxels;
    }
    return out;
}

TEST(Drill, RemovesWhatItTouchesAtTheRateOfForceAndSpeed)
{
    const Drilled d = drill(drilling({{"shape", "sphere"}, {"radius_mm", 3.0}, {"burr_speed_rpm", 60000}}), 45);
    ASSERT_GT(d.removed_voxels, 5u) << "the burr drilled";
    // Voxels of 1 mm^3 go whole: at most what the rate allowed, and at most one voxel's worth
    // less while material stays within reach.
    EXPECT_LE(static_cast<double>(d.removed_voxels), d.allowed_mm3 + 1e-9);
    EXPECT_GE(static_cast<double>(d.removed_voxels), d.allowed_mm3 - 1.0 - 1e-9);
    EXPECT_EQ(d.removed_while_clear, 0u);
}

TEST(Drill, AFasterBurrRemovesMoreAndACylinderDrillsToo)
{
    // Pressed through a soft spring 10 mm past the surface: about the same force for both (the
    // burr stays at the bone's surface as it drills), so three times the speed drills about three
    // times as much.
    const Drilled slow = drill(drilling({{"shape", "sphere"}, {"radius_mm", 3.0}, {"burr_speed_rpm", 20000}, {"coupling_stiffness_n_per_mm", 0.5}}, "dbg", 10.0), 45);
    const Drilled fast = drill(drilling({{"shape", "sphere"}, {"radius_mm", 3.0}, {"burr_speed_rpm", 60000}, {"coupling_stiffness_n_per_mm", 0.5}}, "dbg", 10.0), 45);
    EXPECT_GT(fast.removed_voxels, 2 * slow.removed_voxels) << slow.removed_voxels;
    const Drilled flat = drill(drilling({{"shape", "cylinder"}, {"radius_mm", 2.0}, {"length_mm", 6.0}, {"burr_speed_rpm", 60000}}), 45);
    EXPECT_GE(flat.removed_voxels, 3u) << flat.allowed_mm3;
    EXPECT_GE(static_cast<double>(flat.removed_voxels), flat.allowed_mm3 - 1.0 - 1e-9);
    EXPECT_LE(static_cast<double>(flat.removed_voxels), flat.allowed_mm3 + 1e-9);
}

TEST(Drill, DrillingIsUndoneAsTheViewerUndoesAStroke)
{
    const io::Scene scene = drilling({{"shape", "sphere"}, {"radius_mm", 3.0}, {"burr_speed_rpm", 60000}});
    auto labels = std::make_shared<const grid::LabelGrid>(io::load_scene_object(scene));
    auto method = open_method(scene, labels).method;
    ToolPolicy tools(scene);
    FrameLoop loop(scene, *method, tools);
    UndoHistory history(4);
    ASSERT_TRUE(history.before_stroke(*method));
    const std::size_t triangles = method->surface_mesh().triangles.size();
    std::size_t removed = 0;
    for (int f = 0; f < 35; ++f) removed += loop.next().tools.cut.removed_voxels;
    ASSERT_GT(removed, 0u);
    ASSERT_NE(method->surface_mesh().triangles.size(), triangles);
    ASSERT_TRUE(history.undo(*method));
    EXPECT_EQ(method->surface_mesh().triangles.size(), triangles) << "the drilled hole is filled again";
    EXPECT_EQ(method->cut_count(), 0u);
}

TEST(Drill, IsxfemRefusesItByName)
{
    const io::Scene s = drilling({{"shape", "sphere"}, {"radius_mm", 3.0}}, "isxfem");
    auto labels = std::make_shared<const grid::LabelGrid>(io::load_scene_object(s));
    try {
        (void)open_method(s, labels);
        FAIL() << "no error";
    } catch (const InputError& e) {
        EXPECT_NE(std::string(e.what()).find("cannot drill"), std::string::npos) << e.what();
    }
}

} // namespace
} // namespace vox::sim
