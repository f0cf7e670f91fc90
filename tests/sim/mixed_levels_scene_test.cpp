// A scene on two levels ("levels": {"fine", "coarse", "fine_radius_mm"}): a ball pressed 1 mm into
// a soft block, level 1 around it and level 3 elsewhere, pushes back with the uniform level-1
// block's force to within 5 %, its surface closed (every edge in two triangles, finite) in every
// frame; slid 32 mm across the block, the fine region follows it and the force stays the fine
// block's; a blade cuts a bar on two levels as on the fine level; the keys' errors name what two
// levels do not run with yet.

#include "io/scene.hpp"
#include "sim/dbg_method.hpp"
#include "sim/frame_loop.hpp"
#include "sim/tool_policy.hpp"

#include "bundled_scene.hpp"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <algorithm>
#include <cstdio>
#include <map>
#include <set>

namespace vox::sim {
namespace {

/// A 32 x 32 x 16 mm block on its base, a ball of radius 4 mm touching its top at (15.5, 15.5)
/// and pressed 1 mm in over half a second, then held.
nlohmann::json press(const nlohmann::json& levels)
{
    return {
        {"object", {{"phantom", {{"shape", "block"}, {"size_mm", {32, 32, 16}}, {"voxel_mm", 1}}}, {"levels", levels}}},
        {"materials", {{"default", {{"youngs_modulus_pa", 2e4}, {"poisson_ratio", 0.3}, {"density_kg_m3", 1000}}}}},
        {"solver", {{"type", "dbg"}, {"dt_s", 0.01}, {"rayleigh_mass_per_s", 10.0}}},
        {"gravity_m_s2", {0, 0, 0}},
        {"constraints", {{{"type", "fixed"}, {"box_mm", {{-1, -1, -1}, {33, 33, 0}}}}}},
        {"tools", {{{"name", "ball"}, {"shape", "sphere"}, {"radius_mm", 4}, {"action", "push"}}}},
        {"script",
         {{{"t_s", 0.0}, {"tool", "ball"}, {"position_mm", {15.5, 15.5, 19.5}}},
          {{"t_s", 0.5}, {"tool", "ball"}, {"position_mm", {15.5, 15.5, 18.5}}},
          {{"t_s", 2.0}, {"tool", "ball"}, {"position_mm", {15.5, 15.5, 18.5}}}}},
    };
}

struct Pressed {
    double force_n = 0.0, frame_ms = 0.0;
    std::size_t dofs = 0;
};

Pressed run(const nlohmann::json& levels)
{
    const io::Scene scene = io::parse_scene(press(levels), ::testing::TempDir(), "mixed_press.json");
    std::unique_ptr<Method> method = test::open(scene);
    ToolPolicy tools(scene);
    FrameLoop loop(scene, *method, tools);
    std::vector<double> ms;
    Pressed out;
    for (int f = 0; f < 150; ++f) {
        const FrameStats s = loop.next();
        ms.push_back(s.frame_ms);
        if (f >= 130) out.force_n += s.tools.tools[0].force_n.z() / 20.0;
        // Closed: every edge in exactly two triangles, every vertex finite.
        const surface::SurfaceMesh mesh = method->surface_mesh();
        std::map<std::pair<std::uint32_t, std::uint32_t>, int> edges;
        for (const auto& t : mesh.triangles)
            for (int k = 0; k < 3; ++k) ++edges[std::minmax(static_cast<std::uint32_t>(t[k]), static_cast<std::uint32_t>(t[(k + 1) % 3]))];
        for (const auto& [edge, uses] : edges) EXPECT_EQ(uses, 2) << "frame " << f << ": an open edge";
        for (const Eigen::Vector3d& p : mesh.positions) EXPECT_TRUE(p.allFinite()) << "frame " << f;
    }
    std::sort(ms.begin(), ms.end());
    out.frame_ms = ms[ms.size() / 2];
    out.dofs = method->dof_count();
    return out;
}

TEST(MixedLevelsScene, ABallPressedIntoABlockFeelsTheFineBlocksForce)
{
    const Pressed fine = run(1), mixed = run({{"fine", 1}, {"coarse", 3}, {"fine_radius_mm", 3}}), coarse = run(3);
    std::printf("ball 1 mm into the block: level 1 %.4f N (%zu dofs, %.2f ms a frame), levels 1/3 %.4f N (%zu dofs, %.2f ms), "
                "level 3 %.4f N (%zu dofs, %.2f ms)\n",
                fine.force_n, fine.dofs, fine.frame_ms, mixed.force_n, mixed.dofs, mixed.frame_ms, coarse.force_n, coarse.dofs, coarse.frame_ms);
    ASSERT_GT(fine.force_n, 0.01) << "the ball presses the block";
    EXPECT_NEAR(mixed.force_n / fine.force_n, 1.0, 0.05);
    EXPECT_LT(mixed.dofs, fine.dofs / 3);
}

TEST(MixedLevelsScene, TheKeysNameWhatTwoLevelsDoNotRunWithYet)
{
    auto error = [](nlohmann::json doc) {
        try {
            (void)io::parse_scene(doc, ::testing::TempDir(), "mixed.json");
        } catch (const InputError& e) {
            return std::string(e.what());
        }
        return std::string("no error");
    };
    nlohmann::json doc = press({{"fine", 3}, {"coarse", 2}, {"fine_radius_mm", 5}});
    EXPECT_NE(error(doc).find("object.levels.coarse: must be coarser than \"fine\" (3), got 2"), std::string::npos) << error(doc);
    doc = press({{"fine", 1}, {"coarse", 3}, {"fine_radius_mm", 5}});
    doc["solver"]["type"] = "isxfem";
    EXPECT_NE(error(doc).find("object.levels: two levels run on the branched grid only"), std::string::npos) << error(doc);
    doc = press({{"fine", 1}, {"coarse", 3}});
    EXPECT_NE(error(doc).find("fine_radius_mm"), std::string::npos) << error(doc);
}

/// Whether the surface is closed and finite; a message for the first fault.
std::string closed(const surface::SurfaceMesh& mesh)
{
    std::map<std::pair<std::uint32_t, std::uint32_t>, int> edges;
    for (const auto& t : mesh.triangles)
        for (int k = 0; k < 3; ++k) ++edges[std::minmax(static_cast<std::uint32_t>(t[k]), static_cast<std::uint32_t>(t[(k + 1) % 3]))];
    for (const auto& [edge, uses] : edges)
        if (uses != 2) return "an edge in " + std::to_string(uses) + " triangles";
    for (const Eigen::Vector3d& p : mesh.positions)
        if (!p.allFinite()) return "a vertex not finite";
    return "";
}

/// The ball pressed 1 mm into a 48 x 32 x 16 mm block at x = 8 and slid along x to x = 40.
nlohmann::json slide(const nlohmann::json& levels)
{
    nlohmann::json doc = press(levels);
    doc["object"]["phantom"]["size_mm"] = {48, 32, 16};
    doc["constraints"][0]["box_mm"] = {{-1, -1, -1}, {49, 33, 0}};
    doc["script"] = {{{"t_s", 0.0}, {"tool", "ball"}, {"position_mm", {8.5, 15.5, 19.5}}},
                     {{"t_s", 0.4}, {"tool", "ball"}, {"position_mm", {8.5, 15.5, 18.5}}},
                     {{"t_s", 1.6}, {"tool", "ball"}, {"position_mm", {40.5, 15.5, 18.5}}}};
    return doc;
}

TEST(MixedLevelsScene, TheFineRegionFollowsABallSlidAcrossTheBlock)
{
    std::vector<double> force[2];
    RegionCells end_region;
    std::size_t moves = 0;
    for (int run = 0; run < 2; ++run) {
        const io::Scene scene = io::parse_scene(run == 0 ? slide(1) : slide({{"fine", 1}, {"coarse", 3}, {"fine_radius_mm", 3}}),
                                                ::testing::TempDir(), "mixed_slide.json");
        std::unique_ptr<Method> method = test::open(scene);
        ToolPolicy tools(scene);
        FrameLoop loop(scene, *method, tools);
        for (int f = 0; f < 160; ++f) {
            force[run].push_back(loop.next().tools.tools[0].force_n.z());
            if (run == 1) ASSERT_EQ(closed(method->surface_mesh()), "") << "frame " << f;
        }
        if (run == 1) {
            end_region = dynamic_cast<const DbgMethod&>(*method).simulation().region();
            nlohmann::json summary;
            method->add_summary_figures(summary);
            moves = summary["fine_region_moves"].get<std::size_t>();
        }
    }
    // Level-3 cells are 8 mm wide (cell k spans 8k - 0.5 .. 8k + 7.5 mm): the ball ends at x =
    // 40.5 with its reach (4 + 3 mm) over cells 4 and 5, and cell 3 within half a cell of it; it
    // started over cells 0 to 2, which it has left.
    EXPECT_GE(moves, 3u);
    ASSERT_FALSE(end_region.empty());
    for (const grid::Coord& c : end_region) EXPECT_GE(c.x(), 3) << "a cell the ball has left stays fine";
    EXPECT_TRUE(std::any_of(end_region.begin(), end_region.end(), [](const grid::Coord& c) { return c.x() == 5; }));
    // Along the whole slide (after the press has settled), the force within 5 % of level 1's.
    for (int f = 50; f < 160; f += 5) EXPECT_NEAR(force[1][f] / force[0][f], 1.0, 0.05) << "frame " << f << ": " << force[1][f] << " N against " << force[0][f];
}

TEST(MixedLevelsScene, ABladeCutsABarOnTwoLevelsAsOnTheFineLevel)
{
    // A 40 x 8 x 8 mm bar held at x < 2 is cut through at x = 20 by a blade swept down across it;
    // on two levels (1 within 2 mm of the blade, 3 elsewhere) the same faces open as at level 1,
    // the end falls away, and the surface stays closed.
    const auto bar = [](const nlohmann::json& levels) {
        return nlohmann::json{
            {"object", {{"phantom", {{"shape", "block"}, {"size_mm", {40, 8, 8}}, {"voxel_mm", 1}}}, {"levels", levels}}},
            {"materials", {{"default", {{"youngs_modulus_pa", 1e6}, {"poisson_ratio", 0.3}, {"density_kg_m3", 1000}}}}},
            {"solver", {{"type", "dbg"}, {"dt_s", 0.005}}},
            {"gravity_m_s2", {0, 0, -9.81}},
            {"constraints", {{{"type", "fixed"}, {"box_mm", {{-1, -1, -1}, {2, 9, 9}}}}}},
            {"tools", {{{"name", "blade"}, {"shape", "blade"}, {"size_mm", {20, 0.5, 6}}, {"cut_mode", "separate"}}}},
            {"script",
             {{{"t_s", 0.0}, {"tool", "blade"}, {"position_mm", {19.5, 3.5, 14}}, {"orientation_wxyz", {0.7071068, 0, 0, 0.7071068}}},
              {{"t_s", 0.15}, {"tool", "blade"}, {"position_mm", {19.5, 3.5, -20}}, {"orientation_wxyz", {0.7071068, 0, 0, 0.7071068}}}}},
        };
    };
    std::set<std::vector<int>> faces[2]; // every face opened, [i, j, k, axis]
    for (int run = 0; run < 2; ++run) {
        const io::Scene scene = io::parse_scene(bar(run == 0 ? nlohmann::json(1) : nlohmann::json{{"fine", 1}, {"coarse", 3}, {"fine_radius_mm", 2}}),
                                                ::testing::TempDir(), "mixed_cut.json");
        std::unique_ptr<Method> method = test::open(scene);
        ToolPolicy tools(scene);
        FrameLoop loop(scene, *method, tools);
        for (int f = 0; f < 50; ++f) {
            (void)loop.next();
            ASSERT_EQ(closed(method->surface_mesh()), "") << "frame " << f;
        }
        EXPECT_EQ(method->piece_count(), 2u) << "run " << run;
        for (const auto& cut : method->cuts_since(0))
            for (const auto& face : cut["faces"]) faces[run].insert(face.get<std::vector<int>>());
    }
    EXPECT_EQ(faces[0].size(), 64u) << "an 8 x 8 section";
    EXPECT_EQ(faces[1], faces[0]);
}

} // namespace
} // namespace vox::sim
