// `voxsculpt run` with the Is-XFEM solver, end to end: the bundled bar is cut through by its blade
// over several frames into one crack, its far half falls away while the held half stays, and the
// surface comes out closed along the cut (two closed pieces, the bar's volume between them), and
// along the front of a slit that stops inside it; a blade turning round a half circle as it cuts
// leaves one curved crack; a finger pressing on the cylinder pushes as it does on the branched
// grid; a two-phase knife holds the block while it marks; the haptic loop runs beside it; a scene
// asking Is-XFEM for what it does not do yet is refused with one message naming the key.

#include "app/run_command.hpp"
#include "test_support.hpp"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <utility>
#include <vector>

namespace fs = std::filesystem;
using vox::test::fresh_dir;
using vox::test::quote;
using vox::test::run_voxsculpt;

namespace {

/// A run's final surface (`voxsculpt info` of it), checked closed and consistently oriented, in
/// `pieces` pieces holding `volume_mm3` between them (to `tolerance`: the pieces are elastic).
nlohmann::json closed_pieces(const fs::path& mesh_path, int pieces, double volume_mm3, double tolerance)
{
    const nlohmann::json mesh = vox::test::info_json(mesh_path);
    EXPECT_EQ(mesh["closed"], true);
    EXPECT_EQ(mesh["components"], pieces);
    EXPECT_EQ(mesh["consistently_oriented"], true);
    EXPECT_NEAR(mesh["enclosed_volume_mm3"].get<double>(), volume_mm3, tolerance);
    return mesh;
}

/// The bundled scene `name` with `from` replaced by `to` (each must occur), written to d/scene.json.
fs::path edited_scene(const fs::path& d, const std::string& name, const std::vector<std::pair<std::string, std::string>>& edits)
{
    std::ifstream in(std::string(VOX_SOURCE_DIR) + "/data/scenes/" + name);
    std::stringstream text;
    text << in.rdbuf();
    std::string scene = text.str();
    for (const auto& [from, to] : edits) {
        const std::size_t at = scene.find(from);
        EXPECT_NE(at, std::string::npos) << from;
        if (at != std::string::npos) scene.replace(at, from.size(), to);
    }
    std::ofstream(d / "scene.json") << scene;
    return d / "scene.json";
}

/// The finger's force on the tool along z at the last frame of a run's stats.json.
double last_finger_force_z(const fs::path& stats_path)
{
    std::ifstream in(stats_path);
    const nlohmann::json stats = nlohmann::json::parse(in);
    return stats["frames"].back()["tools"][0]["force_n"][2].get<double>();
}

} // namespace

TEST(IsxfemRun, TheBarIsCutThroughAndItsFarHalfFalls)
{
    const fs::path out = fresh_dir("isxfem_bar");
    const auto r = run_voxsculpt("run " + quote(std::string(VOX_SOURCE_DIR) + "/data/scenes/bar_cut_isxfem.json") + " --frames 30 --out " +
                                 quote(out.string()));
    ASSERT_EQ(r.exit_code, 0) << r.err;
    std::ifstream in(out / "stats.json");
    const nlohmann::json stats = nlohmann::json::parse(in);
    EXPECT_EQ(stats["method"], "isxfem");
    EXPECT_EQ(stats["summary"]["isxfem"]["cuts"], 1);       // one stroke, one crack, however many frames it took
    EXPECT_EQ(stats["summary"]["isxfem"]["cut_tets"], 54);  // the bar's 3 x 3 cells across at level 2, six tetrahedra each
    EXPECT_EQ(stats["summary"]["converged_frames"], 30);
    EXPECT_EQ(stats["summary"]["isxfem"]["crack_faces"], 1); // the bar's cross-section, on both sides
    EXPECT_EQ(stats["summary"]["isxfem"]["slit_faces"], 0);
    EXPECT_EQ(stats["summary"]["isxfem"]["open_crack_chains"], 0);
    int cutting_frames = 0;
    for (const auto& f : stats["frames"]) cutting_frames += f["isxfem"]["cut_tets"].get<int>() > 0;
    EXPECT_GT(cutting_frames, 1); // the blade goes down through it over several frames
    // By 0.3 s the far half has fallen tens of centimetres (free fall from the last cut: 0.5 g t^2).
    EXPECT_GT(stats["frames"].back()["max_displacement_mm"].get<double>(), 150.0);
    // Closed along the cut: two closed pieces holding the bar's 100 x 10 x 10 mm between them (the
    // pieces are elastic, nu = 0.3: their volume follows the deformation to about a percent).
    const nlohmann::json mesh = closed_pieces(out / "final.obj", 2, 1e4, 150.0);
    // The held half stays up (its top still near z = 9.5 mm), the far half is far below.
    EXPECT_GT(mesh["world_bbox_mm"]["max"][2].get<double>(), 8.0);
    EXPECT_LT(mesh["world_bbox_mm"]["min"][2].get<double>(), -150.0);
}

TEST(IsxfemRun, ASlitThatStopsInsideTheBarIsClosedAlongItsFront)
{
    // The same blade stopped with its edge at the bar's bottom face: the soft bar gives way
    // under it, so the crack reaches about two thirds down and stops inside.
    const fs::path d = fresh_dir("isxfem_slit");
    const std::string down = "\"position_mm\": [50.3, 5, -15]", stop = "\"position_mm\": [50.3, 5, 10]";
    const fs::path scene = edited_scene(d, "bar_cut_isxfem.json", {{down, stop}, {down, stop}}); // both poses below the bar
    const auto r = run_voxsculpt("run " + quote(scene.string()) + " --frames 30 --out " + quote((d / "out").string()));
    ASSERT_EQ(r.exit_code, 0) << r.err;
    std::ifstream in(d / "out" / "stats.json");
    const nlohmann::json stats = nlohmann::json::parse(in);
    EXPECT_GT(stats["summary"]["isxfem"]["cut_tets"].get<int>(), 0);
    EXPECT_LT(stats["summary"]["isxfem"]["cut_tets"].get<int>(), 54); // not through
    EXPECT_EQ(stats["summary"]["isxfem"]["slit_faces"], 1);
    EXPECT_EQ(stats["summary"]["isxfem"]["open_crack_chains"], 0);
    closed_pieces(d / "out" / "final.obj", 1, 1e4, 150.0);
}

TEST(IsxfemRun, AWaveringBladeCutsOnAlongItsStrokesPlane)
{
    // A blade drawn down through the bar (held at both ends, stiff), 0.8 mm a frame, tilting by
    // +-0.5 degrees about the vertical from one frame to the next as a hand does: no single
    // frame's sweep covers a tetrahedron, and the pressure at its edge holds in some frames only,
    // so the cut relies on the stroke going on in one plane through every frame it touches and
    // adding up the sweeps of those that cut. (A new plane every frame cut half the path in three
    // cuts.)
    const fs::path d = fresh_dir("isxfem_wavering");
    std::ostringstream script;
    for (int k = 0; k <= 30; ++k) {
        const double half = (90.0 + (k % 2 ? 0.5 : -0.5)) * 3.14159265358979323846 / 360.0;
        script << (k ? ",\n" : "") << "{\"t_s\": " << 0.01 * k << ", \"tool\": \"blade\", \"position_mm\": [50.3, 5, " << 20.5 - 0.8 * k
               << "], \"orientation_wxyz\": [" << std::cos(half) << ", 0, 0, " << std::sin(half) << "]}";
    }
    std::ofstream(d / "scene.json") << R"({
        "object": {"phantom": {"shape": "beam", "size_mm": [100, 10, 10], "voxel_mm": 1.0}, "levels": 2},
        "materials": {"default": {"youngs_modulus_pa": 1e7, "poisson_ratio": 0.3, "density_kg_m3": 1000}},
        "solver": {"type": "isxfem", "k": 0.1, "dt_s": 0.01, "cg_tolerance": 1e-6, "cg_max_iterations": 2000},
        "gravity_m_s2": [0, 0, -9.81],
        "constraints": [{"type": "fixed", "box_mm": [[-1, -1, -1], [2, 11, 11]]}, {"type": "fixed", "box_mm": [[98, -1, -1], [101, 11, 11]]}],
        "tools": [{"name": "blade", "shape": "blade", "size_mm": [40, 1, 20], "cut_pressure_pa": 1}],
        "script": [)" << script.str() << R"(]
    })";
    const auto r = run_voxsculpt("run " + quote((d / "scene.json").string()) + " --frames 30 --out " + quote((d / "out").string()));
    ASSERT_EQ(r.exit_code, 0) << r.err;
    std::ifstream in(d / "out" / "stats.json");
    const nlohmann::json stats = nlohmann::json::parse(in);
    EXPECT_EQ(stats["summary"]["isxfem"]["cuts"], 1);
    EXPECT_EQ(stats["summary"]["isxfem"]["cut_tets"], 54); // the bar's 3 x 3 cells across, six tetrahedra each
    EXPECT_EQ(stats["summary"]["isxfem"]["open_crack_chains"], 0);
}

TEST(IsxfemRun, AHalfCircleIncisionIsOneCutAndItsFlapFalls)
{
    // A 2 mm blade drawn into a slab (held along its back) from its front edge, round a half circle
    // of radius 12 mm and out again through its full height, turning by 180 degrees: the cut follows
    // the blade's swept surface, one crack with no tetrahedron cut twice, and the flap it cuts out
    // falls away closed.
    const fs::path d = fresh_dir("isxfem_flap");
    const auto r = run_voxsculpt("run " + quote(std::string(VOX_SOURCE_DIR) + "/data/scenes/slab_flap_cut_isxfem.json") + " --frames 70 --out " +
                                 quote((d / "out").string()));
    ASSERT_EQ(r.exit_code, 0) << r.err;
    std::ifstream in(d / "out" / "stats.json");
    const nlohmann::json stats = nlohmann::json::parse(in);
    EXPECT_EQ(stats["summary"]["isxfem"]["cuts"], 1);
    EXPECT_EQ(stats["summary"]["isxfem"]["recut_tets"], 0);
    EXPECT_EQ(stats["summary"]["isxfem"]["crack_faces"], 1);
    EXPECT_EQ(stats["summary"]["isxfem"]["open_crack_chains"], 0);
    const nlohmann::json mesh = closed_pieces(d / "out" / "final.obj", 2, 40.0 * 40.0 * 10.0, 200.0);
    EXPECT_LT(mesh["world_bbox_mm"]["min"][2].get<double>(), -20.0); // the flap, 0.1 s after the blade came out: 0.5 g t^2 = 49 mm
}

TEST(IsxfemRun, AFingerPushesOnTheTetrahedraAsOnTheBranchedGrid)
{
    // The cylinder at level 2, its finger 2 mm into the top by frame 170 (0.85 s).
    const fs::path d = fresh_dir("isxfem_push");
    fs::create_directories(d / "dbg");
    fs::create_directories(d / "isxfem");
    const fs::path dbg = edited_scene(d / "dbg", "cylinder.json", {{"\"levels\": 1", "\"levels\": 2"}});
    const fs::path isxfem = edited_scene(d / "isxfem", "cylinder.json", {{"\"levels\": 1", "\"levels\": 2"}, {"\"type\": \"dbg\"", "\"type\": \"isxfem\""}});
    for (const fs::path& scene : {dbg, isxfem}) {
        const auto r = run_voxsculpt("run " + quote(scene.string()) + " --frames 170 --out " + quote((scene.parent_path() / "out").string()));
        ASSERT_EQ(r.exit_code, 0) << r.err;
    }
    const double branched = last_finger_force_z(d / "dbg" / "out" / "stats.json");
    const double tetrahedra = last_finger_force_z(d / "isxfem" / "out" / "stats.json");
    EXPECT_GT(branched, 0.005); // the object pushes the finger up
    // Linear tetrahedra are stiffer than the branched hexahedra at this coarse level: the same
    // indentation pushes back harder (at level 1 the two agree to 10 %).
    EXPECT_GT(tetrahedra, 0.8 * branched);
    EXPECT_LT(tetrahedra, 2.5 * branched);
}

TEST(IsxfemRun, ATwoPhaseKnifeHoldsTheBlockWhileItMarksThenCuts)
{
    // The knife of press_and_cut_two_phase.json on the tetrahedra: while it touches, the block is
    // held (no step) and the force rises; at the cut pressure the marked path is cut at once and
    // the block moves again.
    const fs::path d = fresh_dir("isxfem_two_phase");
    const fs::path scene = edited_scene(d, "press_and_cut_two_phase.json", {{"\"type\": \"dbg\"", "\"type\": \"isxfem\""}});
    const auto r = run_voxsculpt("run " + quote(scene.string()) + " --out " + quote((d / "out").string()));
    ASSERT_EQ(r.exit_code, 0) << r.err;
    std::ifstream in(d / "out" / "stats.json");
    const nlohmann::json stats = nlohmann::json::parse(in);
    int held = 0, last_held = -1, first_cut = -1;
    double force_held = 0.0;
    for (const auto& f : stats["frames"]) {
        const int frame = f["frame"].get<int>();
        if (f["object_held"].get<bool>()) {
            EXPECT_TRUE(last_held < 0 || last_held == frame - 1) << frame; // one marking, while it touches
            ++held;
            last_held = frame;
            force_held = std::max(force_held, f["tools"][0]["force_n"][2].get<double>());
        }
        if (f["isxfem"]["cut_tets"].get<int>() > 0 && first_cut < 0) first_cut = frame;
    }
    EXPECT_GE(held, 3);
    EXPECT_GT(force_held, 0.01); // the force rose while the block was held
    ASSERT_GT(first_cut, last_held); // the cuts come once the marking has reached the pressure
    EXPECT_GT(stats["summary"]["isxfem"]["cut_tets"].get<int>(), 0);
}

TEST(IsxfemRun, TheHapticLoopRunsBesideIt)
{
    // One second of the 1 kHz loop against Is-XFEM pressing and cutting (the timings are the
    // benchmark's business, not this test's): it runs, ticks and publishes snapshots with points.
    const auto r = run_voxsculpt("bench haptics --seconds 1 --isxfem");
    ASSERT_EQ(r.exit_code, 0) << r.err;
    const std::size_t row = r.out.find("\n| ", r.out.find("|---"));
    ASSERT_NE(row, std::string::npos) << r.out;
    std::stringstream cells(r.out.substr(row + 3));
    int ticks = 0;
    cells >> ticks;
    EXPECT_GT(ticks, 500) << r.out;
}

TEST(IsxfemRun, WhatItCannotDoYetIsRefusedByName)
{
    const fs::path d = fresh_dir("isxfem_refused");
    std::ifstream in(std::string(VOX_SOURCE_DIR) + "/data/scenes/wet_push.json");
    std::stringstream text;
    text << in.rdbuf();
    std::string scene = text.str();
    const std::string key = "\"type\": \"dbg\"";
    ASSERT_NE(scene.find(key), std::string::npos);
    scene.replace(scene.find(key), key.size(), "\"type\": \"isxfem\"");
    std::ofstream(d / "scene.json") << scene;
    const auto r = run_voxsculpt("run " + quote((d / "scene.json").string()) + " --out " + quote((d / "out").string()));
    EXPECT_EQ(r.exit_code, 2);
    EXPECT_NE(r.err.find("wet_regions"), std::string::npos) << r.err; // its pushing fingers alone would run
    EXPECT_NE(r.err.find("isxfem"), std::string::npos) << r.err;
    EXPECT_FALSE(fs::exists(d / "out" / "stats.json"));
}

TEST(IsxfemRun, CompareRunsEveryMethodOnTheSameScene)
{
    const fs::path out = fresh_dir("isxfem_compare");
    const auto r = run_voxsculpt("bench compare " + quote(std::string(VOX_SOURCE_DIR) + "/data/scenes/bar_cut_isxfem.json") +
                                 " --frames 12 --out " + quote(out.string()));
    ASSERT_EQ(r.exit_code, 0) << r.err;
    std::ifstream in(out / "compare-bar_cut_isxfem.md");
    std::stringstream md;
    md << in.rdbuf();
    for (const std::string method : {"| dbg |", "| Is-XFEM (k = 0.1) |", "| XFEM (k = 0) |", "| shape matching |"}) {
        const std::size_t row = md.str().find(method);
        ASSERT_NE(row, std::string::npos) << method;
        const std::string line = md.str().substr(row, md.str().find('\n', row) - row);
        EXPECT_NE(line.find("12 of 12"), std::string::npos) << line; // every frame of each method converged
    }
    // Every column measured for every method, by the same code: the same figures, none missing.
    std::ifstream json_in(out / "compare-bar_cut_isxfem.json");
    const nlohmann::json data = nlohmann::json::parse(json_in);
    ASSERT_EQ(data["methods"].size(), 4u);
    for (const nlohmann::json& m : data["methods"]) {
        EXPECT_EQ(m.size(), data["methods"][0].size()) << m["method"];
        for (const auto& [key, value] : m.items()) EXPECT_FALSE(value.is_null()) << m["method"] << " " << key;
        EXPECT_EQ(m["frame_ms"].size(), 12u) << m["method"];
        EXPECT_GT(m["cut_update_ms"].size(), 0u) << m["method"] << ": the blade cut";
        EXPECT_NEAR(m["volume_before_mm3"].get<double>(), 1e4, 100.0) << m["method"]; // the 100 x 10 x 10 mm bar
        EXPECT_NEAR(m["volume_after_mm3"].get<double>(), m["volume_before_mm3"].get<double>(), 200.0) << m["method"]; // separating keeps it
    }
}
