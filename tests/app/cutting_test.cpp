// Cutting end to end: the bundled cutting scenes run headless, checked on what they must show.

#include "app/run_command.hpp"
#include "test_support.hpp"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <filesystem>
#include <fstream>
#include <algorithm>
#include <cmath>
#include <sstream>
#include <vector>

namespace fs = std::filesystem;
using vox::test::fresh_dir;
using vox::test::info_json;
using vox::test::quote;
using vox::test::run_voxsculpt;

namespace {


/// Runs a bundled scene (data/scenes/NAME.json) into `out` with extra options; returns stats.json.
nlohmann::json run_bundled(const std::string& name, const fs::path& out, const std::string& options = "")
{
    const auto r = run_voxsculpt("run " + quote(std::string(VOX_SOURCE_DIR) + "/data/scenes/" + name + ".json") + " --out " +
                                 quote(out.string()) + " " + options);
    EXPECT_EQ(r.exit_code, 0) << r.err;
    std::ifstream in(out / "stats.json");
    return nlohmann::json::parse(in);
}

/// Every frame mesh written into `dir` is a closed surface.
void expect_all_frames_closed(const fs::path& dir)
{
    int checked = 0;
    for (const auto& entry : fs::directory_iterator(dir)) {
        if (entry.path().extension() != ".obj") continue;
        const nlohmann::json j = info_json(entry.path());
        EXPECT_EQ(j["closed"], true) << entry.path();
        EXPECT_EQ(j["consistently_oriented"], true) << entry.path();
        ++checked;
    }
    EXPECT_GT(checked, 0);
}

/// Lowest z of the surface vertices within 1.5 mm (x, y) of a point, from an OBJ file.
double lowest_top(const fs::path& obj, double x, double y)
{
    std::ifstream in(obj);
    std::string line;
    double lowest = 1e9;
    while (std::getline(in, line)) {
        if (line.rfind("v ", 0) != 0) continue;
        std::istringstream s(line.substr(2));
        double px = 0, py = 0, pz = 0;
        s >> px >> py >> pz;
        if (std::abs(px - x) < 1.5 && std::abs(py - y) < 1.5 && pz > 5.0) lowest = std::min(lowest, pz);
    }
    return lowest;
}

} // namespace

TEST(Cutting, ThroughCutSeparatesTheCylinderIntoTwoClosedPiecesAndKeepsEveryVoxel)
{
    // The scene's blade sweeps through the hanging cylinder in separate mode; a mesh every frame.
    const fs::path out = fresh_dir("cut_cylinder");
    const nlohmann::json stats = run_bundled("cylinder_cut", out, "--frames 60");
    const nlohmann::json& s = stats["summary"];
    EXPECT_EQ(s["pieces"], 2);
    EXPECT_GT(s["separated_faces"].get<int>(), 0);
    EXPECT_EQ(s["removed_voxels"], 0);
    // Separate mode keeps every voxel and so every gram: 4,800 voxels of 1 mm^3 at 1100 kg/m^3.
    EXPECT_EQ(s["voxels"], 4800);
    EXPECT_NEAR(s["mass_kg"].get<double>(), 4800 * 1e-9 * 1100, 1e-12);
    const nlohmann::json final_surface = info_json(out / "final.obj");
    EXPECT_EQ(final_surface["closed"], true);
    EXPECT_EQ(final_surface["components"], 2);
    // The lower piece falls away: after the cut its displacement grows like g t^2 / 2.
    EXPECT_GT(s["final_max_displacement_mm"].get<double>(), 100.0);
    // Per-frame phases are reported.
    for (const char* key : {"collision_ms", "propagation_ms", "grid_update_ms", "remesh_ms", "fem_update_ms", "removed_voxels",
                            "separated_faces"})
        EXPECT_TRUE(stats["frames"][0].contains(key)) << key;
}

TEST(Cutting, SurfaceStaysClosedAfterEveryCutStep)
{
    // Every frame's surface, in both modes: the cylinder (separate) and the knife of the broad /
    // sharp scene (remove).
    const fs::path separate = fresh_dir("cut_every_frame_separate");
    {
        std::ifstream in(std::string(VOX_SOURCE_DIR) + "/data/scenes/cylinder_cut.json");
        std::stringstream text;
        text << in.rdbuf();
        std::string scene = text.str();
        const std::string every = "\"mesh_every_n_frames\": 10";
        scene.replace(scene.find(every), every.size(), "\"mesh_every_n_frames\": 1");
        std::ofstream(separate / "scene.json") << scene;
    }
    ASSERT_EQ(run_voxsculpt("run " + quote((separate / "scene.json").string()) + " --frames 16 --out " + quote((separate / "out").string()))
                  .exit_code,
              0);
    expect_all_frames_closed(separate / "out");

    const fs::path removal = fresh_dir("cut_every_frame_remove");
    const nlohmann::json stats = run_bundled("push_broad_vs_sharp", removal, "--frames 40");
    EXPECT_GT(stats["summary"]["removed_voxels"].get<int>(), 0);
    expect_all_frames_closed(removal);
}

TEST(Cutting, ABroadPushCutsNothingWhereASharpOneCuts)
{
    const fs::path out = fresh_dir("cut_broad_sharp");
    const nlohmann::json stats = run_bundled("push_broad_vs_sharp", out);
    bool paddle_cut = false, knife_cut = false;
    double paddle_force = 0.0, knife_force = 0.0;
    for (const nlohmann::json& f : stats["frames"]) {
        paddle_cut = paddle_cut || f["tools"][0]["cut"].get<bool>();
        knife_cut = knife_cut || f["tools"][1]["cut"].get<bool>();
        paddle_force = std::max(paddle_force, f["tools"][0]["force_n"][2].get<double>());
        knife_force = std::max(knife_force, f["tools"][1]["force_n"][2].get<double>());
    }
    EXPECT_FALSE(paddle_cut);
    EXPECT_TRUE(knife_cut);
    // The paddle pushes with more force than the knife, spread over more area.
    EXPECT_GT(paddle_force, knife_force);
    EXPECT_EQ(stats["summary"]["pieces"], 1);
}

TEST(Cutting, TheUTubesArmsComeApart)
{
    // One coarse cell holds the base and both arms' feet: cutting the base splits it into two
    // superimposed elements, and the free arm falls.
    const fs::path out = fresh_dir("cut_utube");
    const nlohmann::json stats = run_bundled("utube_cut", out);
    EXPECT_EQ(stats["elements"], 7);
    EXPECT_EQ(stats["summary"]["final_elements"], 8);
    EXPECT_EQ(stats["summary"]["pieces"], 2);
    EXPECT_EQ(info_json(out / "final.obj")["components"], 2);
    EXPECT_GT(stats["summary"]["final_max_displacement_mm"].get<double>(), 50.0);
}

TEST(Cutting, AWettedRegionIsPushedFurtherThanADryOne)
{
    // Identical spheres press the same 3 mm into dry and soaked clay and lift off: the soaked side
    // resists with less force and keeps a deeper dent.
    const fs::path out = fresh_dir("cut_wet_push");
    const nlohmann::json stats = run_bundled("wet_push", out);
    double dry_force = 0.0, wet_force = 0.0;
    for (const nlohmann::json& f : stats["frames"]) {
        dry_force = std::max(dry_force, f["tools"][0]["force_n"][2].get<double>());
        wet_force = std::max(wet_force, f["tools"][1]["force_n"][2].get<double>());
    }
    EXPECT_LT(wet_force, 0.6 * dry_force);
    const double dry_top = lowest_top(out / "final.obj", 9.5, 9.5);
    const double wet_top = lowest_top(out / "final.obj", 29.5, 9.5);
    EXPECT_LT(dry_top, 9.5);            // a lasting dent in the dry clay too
    EXPECT_LT(wet_top, dry_top - 0.1);  // deeper in the wet
}

TEST(Cutting, AWettingToolWetsWhatItTouchesAndNothingElse)
{
    const fs::path d = fresh_dir("cut_wet_tool");
    auto scene = [](const std::string& action) {
        return R"({"object": {"phantom": {"shape": "block", "size_mm": [16, 8, 8]}, "levels": 1},
            "constraints": [{"type": "fixed", "box_mm": [[-1, -1, -1], [17, 9, 0]]}],
            "tools": [{"name": "sponge", "shape": "sphere", "radius_mm": 2, "action": ")" +
               action + R"("}],
            "script": [{"t_s": 0, "tool": "sponge", "position_mm": [3.5, 3.5, 9.5]},
                       {"t_s": 0.2, "tool": "sponge", "position_mm": [3.5, 3.5, 8.0]}]})";
    };
    std::ofstream(d / "wet.json") << scene("wet");
    std::ofstream(d / "push.json") << scene("push");
    for (const char* name : {"wet", "push"})
        ASSERT_EQ(run_voxsculpt("run " + quote((d / (std::string(name) + ".json")).string()) + " --out " + quote((d / name).string()))
                      .exit_code,
                  0);
    auto summary = [&](const char* name) {
        std::ifstream in(d / name / "stats.json");
        return nlohmann::json::parse(in)["summary"];
    };
    const nlohmann::json wet = summary("wet"), push = summary("push");
    // The sphere touches a corner region of the 8 x 4 x 4-element block: some elements, not all.
    EXPECT_GT(wet["wet_elements"].get<int>(), 0);
    EXPECT_LT(wet["wet_elements"].get<int>(), 128);
    EXPECT_EQ(push["wet_elements"], 0);
}

TEST(Cutting, ADeviceRecordingReplaysTheSameCutExactly)
{
    // The knife of press_and_cut_two_phase.json driven through the haptic loop (lockstep, 1 ms
    // ticks), recorded; replaying the recording gives the same cut and the same surface, bit for bit.
    const fs::path d = fresh_dir("cut_record_replay");
    const std::string scene = quote(std::string(VOX_SOURCE_DIR) + "/data/scenes/press_and_cut_two_phase.json");
    const std::string recording = quote((d / "knife.csv").string());
    auto r = run_voxsculpt("run " + scene + " --frames 150 --device script --record " + recording + " --out " + quote((d / "live").string()));
    ASSERT_EQ(r.exit_code, 0) << r.err;
    r = run_voxsculpt("run " + scene + " --frames 150 --replay " + recording + " --out " + quote((d / "replay").string()));
    ASSERT_EQ(r.exit_code, 0) << r.err;
    auto slurp = [](const fs::path& p) {
        std::ifstream in(p, std::ios::binary);
        std::stringstream s;
        s << in.rdbuf();
        return s.str();
    };
    EXPECT_EQ(slurp(d / "live" / "final.obj"), slurp(d / "replay" / "final.obj"));
    EXPECT_EQ(slurp(d / "live" / "forces.csv"), slurp(d / "replay" / "forces.csv"));
    std::ifstream a(d / "live" / "stats.json"), b(d / "replay" / "stats.json");
    const nlohmann::json live = nlohmann::json::parse(a), replay = nlohmann::json::parse(b);
    EXPECT_GT(live["summary"]["separated_faces"].get<int>(), 0);
    EXPECT_EQ(live["summary"]["separated_faces"], replay["summary"]["separated_faces"]);
    EXPECT_EQ(live["summary"]["separated_voxels"], replay["summary"]["separated_voxels"]);
}

namespace {
struct ForceRow {
    double t = 0, z = 0, f = 0;
};
std::vector<ForceRow> read_forces(const fs::path& csv)
{
    std::ifstream in(csv);
    std::string line;
    std::getline(in, line);
    EXPECT_EQ(line, "t_s,x_mm,y_mm,z_mm,fx_n,fy_n,fz_n");
    std::vector<ForceRow> rows;
    while (std::getline(in, line)) {
        std::replace(line.begin(), line.end(), ',', ' ');
        std::istringstream s(line);
        double t, x, y, z, fx, fy, fz;
        s >> t >> x >> y >> z >> fx >> fy >> fz;
        rows.push_back({t, z, std::sqrt(fx * fx + fy * fy + fz * fz)});
    }
    return rows;
}
/// Time of the first frame that cut.
double first_cut_s(const nlohmann::json& stats)
{
    for (const nlohmann::json& f : stats["frames"])
        if (f["separated_faces"].get<int>() > 0) return f["t_s"].get<double>();
    return -1.0;
}
} // namespace

TEST(Cutting, PressAndCutForcesRiseAndDropInTwoPhasesAndPlateauOtherwise)
{
    const fs::path d = fresh_dir("cut_press_forces");
    const nlohmann::json two = run_bundled("press_and_cut_two_phase", d / "two", "--device script");
    const nlohmann::json one = run_bundled("press_and_cut", d / "one", "--device script");
    EXPECT_TRUE(fs::exists(d / "two" / "forces.svg"));

    // Two-phase: the block is held while the knife marks the cut, the force rises until the cut
    // and drops by at least a fifth right after it.
    int held = 0;
    for (const nlohmann::json& f : two["frames"]) held += f["object_held"].get<bool>();
    EXPECT_GT(held, 5);
    const double cut = first_cut_s(two);
    ASSERT_GT(cut, 0.0);
    const std::vector<ForceRow> rows = read_forces(d / "two" / "forces.csv");
    double peak = 0.0, after = 1e9;
    for (const ForceRow& r : rows) {
        if (r.t <= cut) peak = std::max(peak, r.f);
        if (r.t > cut && r.t < cut + 0.03) after = std::min(after, r.f);
    }
    EXPECT_GT(peak, 0.2);
    EXPECT_LT(after, 0.8 * peak);

    // Continuous: the knife cuts in several frames, and while the device goes on down (to 2 s) it
    // goes on cutting, so the force levels off instead of climbing with the coupling spring to its
    // clamp: no stretch of the press after the first cut goes 0.3 s without one, and the mean force
    // over the whole press after it is close to its mean just after cutting began. Close, not
    // equal: the force is a sawtooth (rising between cuts, dropping at each), and which frames cut
    // is decided by a pressure threshold, so solves that differ by round-off (both converged) cut
    // at different frames after the eighth cut (measured: longest stretch 0.11 and 0.24 s).
    std::vector<double> cut_at;
    for (const nlohmann::json& f : one["frames"])
        if (f["separated_faces"].get<int>() > 0) cut_at.push_back(f["t_s"].get<double>());
    EXPECT_GE(cut_at.size(), 3u);
    const double start = first_cut_s(one);
    ASSERT_GT(start, 0.0);
    ASSERT_LT(start, 1.7);
    double longest = 0.0;
    for (std::size_t k = 1; k < cut_at.size() && cut_at[k - 1] < 2.0; ++k) longest = std::max(longest, std::min(cut_at[k], 2.0) - cut_at[k - 1]);
    EXPECT_LT(longest, 0.3);
    double early = 0.0, press = 0.0;
    int n_early = 0, n_press = 0;
    for (const ForceRow& r : read_forces(d / "one" / "forces.csv")) {
        if (r.t > start && r.t <= start + 0.25) early += r.f, ++n_early;
        if (r.t > start && r.t <= 2.0) press += r.f, ++n_press;
    }
    ASSERT_GT(n_early * n_press, 0);
    EXPECT_LT(press / n_press, 1.5 * early / n_early);
}

TEST(Cutting, DeviceOptionsRefuseWhatCannotBeDone)
{
    const std::string scene = quote(std::string(VOX_SOURCE_DIR) + "/data/scenes/press_and_cut.json");
    const fs::path d = fresh_dir("cut_device_errors");
    auto r = run_voxsculpt("run " + scene + " --record " + quote((d / "x.csv").string()) + " --out " + quote(d.string()));
    EXPECT_EQ(r.exit_code, 2);
    EXPECT_NE(r.err.find("--record"), std::string::npos) << r.err;
    r = run_voxsculpt("run " + scene + " --device script --tool spoon --out " + quote(d.string()));
    EXPECT_EQ(r.exit_code, 2);
    EXPECT_NE(r.err.find("spoon"), std::string::npos) << r.err;
    r = run_voxsculpt("run " + scene + " --replay " + quote((d / "missing.csv").string()) + " --out " + quote(d.string()));
    EXPECT_EQ(r.exit_code, 2);
    EXPECT_NE(r.err.find("missing.csv"), std::string::npos) << r.err;
    // Several devices: one --tool per --device, each tool driven once, a replay on its own.
    r = run_voxsculpt("run " + scene + " --device script --device script --tool knife --out " + quote(d.string()));
    EXPECT_EQ(r.exit_code, 2);
    EXPECT_NE(r.err.find("give one per --device"), std::string::npos) << r.err;
    r = run_voxsculpt("run " + scene + " --device script --tool knife --device script --tool knife --out " + quote(d.string()));
    EXPECT_EQ(r.exit_code, 2);
    EXPECT_NE(r.err.find("driven by two devices"), std::string::npos) << r.err;
    r = run_voxsculpt("run " + scene + " --device script --replay " + quote((d / "x.csv").string()) + " --out " + quote(d.string()));
    EXPECT_EQ(r.exit_code, 2);
    EXPECT_NE(r.err.find("--replay and --device"), std::string::npos) << r.err;
    EXPECT_FALSE(fs::exists(d / "x.csv"));
}
