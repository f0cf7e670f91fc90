// Both methods wherever a user goes, run as a user runs them: every bundled scene with each
// method (refused only by name, where docs/isxfem.md says why), the viewer in a window on a
// virtual display, and device runs recorded and replayed bit for bit.

#include "app/run_command.hpp"
#include "test_support.hpp"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>
#include <stb/stb_image.h>

#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <memory>
#include <sstream>

namespace fs = std::filesystem;
using vox::test::fresh_dir;
using vox::test::quote;
using vox::test::run_voxsculpt;

namespace {

const char* const k_methods[] = {"dbg", "isxfem"};

std::string slurp(const fs::path& p)
{
    std::ifstream in(p, std::ios::binary);
    std::stringstream s;
    s << in.rdbuf();
    return s.str();
}

/// What Is-XFEM refuses, by the key the message names (docs/isxfem.md, "What it does not do").
bool refused_by_name(const std::string& err)
{
    for (const char* key : {"wet_regions", "loads", "materials", "solver.mode", "object.levels", "solver.preconditioner", ".cut_mode", "tools["})
        if (err.find(key) != std::string::npos && err.find("isxfem") != std::string::npos) return true;
    return false;
}

} // namespace

TEST(MethodsEverywhere, EveryBundledSceneRunsTwentyFramesWithEachMethod)
{
    const fs::path d = fresh_dir("methods_every_scene");
    int ran[2] = {0, 0}, refused = 0;
    for (const auto& entry : fs::directory_iterator(fs::path(VOX_SOURCE_DIR) / "data" / "scenes")) {
        if (entry.path().extension() != ".json") continue;
        for (int m = 0; m < 2; ++m) {
            const fs::path out = d / (entry.path().stem().string() + "_" + k_methods[m]);
            const auto r = run_voxsculpt("run " + quote(entry.path().string()) + " --solver " + k_methods[m] + " --frames 20 --out " +
                                         quote(out.string()));
            if (r.exit_code == 0) {
                ++ran[m];
                std::ifstream in(out / "stats.json");
                const nlohmann::json stats = nlohmann::json::parse(in);
                EXPECT_EQ(stats["method"], k_methods[m]) << entry.path();
                EXPECT_EQ(stats["frames"].size(), 20u) << entry.path();
                EXPECT_TRUE(fs::exists(out / "final.obj")) << entry.path();
                continue;
            }
            // The branched grid runs everything; Is-XFEM refuses what it cannot do, by name.
            EXPECT_EQ(m, 1) << entry.path() << ": " << r.err;
            EXPECT_EQ(r.exit_code, 2) << entry.path() << ": " << r.err;
            EXPECT_TRUE(refused_by_name(r.err)) << entry.path() << ": " << r.err;
            EXPECT_FALSE(fs::exists(out / "stats.json")) << entry.path();
            ++refused;
        }
    }
    EXPECT_GE(ran[0], 18);
    EXPECT_GE(ran[1], 9) << "Is-XFEM refused " << refused;
}

class EachMethodEndToEnd : public ::testing::TestWithParam<const char*> {};

TEST_P(EachMethodEndToEnd, ADeviceRunRecordedReplaysBitForBitOnThreeScenes)
{
    // A tool driven through the haptic loop (lockstep, 1 ms ticks) following its script, recorded;
    // replaying the recording gives the same surface and forces, bit for bit.
    for (const auto& [scene_name, frames] : {std::pair{"press_and_cut_two_phase.json", 150}, {"cylinder_cut.json", 60}, {"cylinder.json", 180}}) {
        const fs::path d = fresh_dir(std::string("record_replay_") + GetParam() + "_" + fs::path(scene_name).stem().string());
        const std::string scene = quote(std::string(VOX_SOURCE_DIR) + "/data/scenes/" + scene_name);
        const std::string recording = quote((d / "tool.csv").string());
        const std::string common = " --solver " + std::string(GetParam()) + " --frames " + std::to_string(frames) + " ";
        auto r = run_voxsculpt("run " + scene + common + "--device script --record " + recording + " --out " + quote((d / "live").string()));
        ASSERT_EQ(r.exit_code, 0) << scene_name << ": " << r.err;
        r = run_voxsculpt("run " + scene + common + "--replay " + recording + " --out " + quote((d / "replay").string()));
        ASSERT_EQ(r.exit_code, 0) << scene_name << ": " << r.err;
        EXPECT_EQ(slurp(d / "live" / "final.obj"), slurp(d / "replay" / "final.obj")) << scene_name;
        EXPECT_EQ(slurp(d / "live" / "forces.csv"), slurp(d / "replay" / "forces.csv")) << scene_name;
        std::ifstream in(d / "live" / "forces.csv");
        std::string header, line;
        std::getline(in, header);
        bool pushed = false; // the device felt the object at some tick
        while (std::getline(in, line) && !pushed) {
            std::istringstream cells(line);
            std::string cell;
            for (int c = 0; c < 7 && std::getline(cells, cell, ','); ++c)
                if (c >= 4 && std::abs(std::stod(cell)) > 1e-6) pushed = true;
        }
        EXPECT_TRUE(pushed) << scene_name;
    }
}

TEST_P(EachMethodEndToEnd, TwoDevicesAtOnceAreRecordedAndReplayedBitForBit)
{
    // data/scenes/two_hands.json with a device per tool, as a user runs it: a finger holds the
    // block while a knife cuts it; each device's forces in its own file, both in the recording.
    const fs::path d = fresh_dir(std::string("two_hands_") + GetParam());
    const std::string scene = quote(std::string(VOX_SOURCE_DIR) + "/data/scenes/two_hands.json");
    const std::string recording = quote((d / "hands.csv").string());
    const std::string common = " --solver " + std::string(GetParam()) + " --frames 120 ";
    auto r = run_voxsculpt("run " + scene + common + "--device script --tool finger --device script --tool knife --record " + recording +
                           " --out " + quote((d / "live").string()));
    ASSERT_EQ(r.exit_code, 0) << r.err;
    r = run_voxsculpt("run " + scene + common + "--replay " + recording + " --out " + quote((d / "replay").string()));
    ASSERT_EQ(r.exit_code, 0) << r.err;
    for (const char* file : {"final.obj", "forces.csv", "forces_2.csv"}) EXPECT_EQ(slurp(d / "live" / file), slurp(d / "replay" / file)) << file;
    std::ifstream in(d / "live" / "stats.json");
    const nlohmann::json stats = nlohmann::json::parse(in);
    ASSERT_EQ(stats["devices"].size(), 2u);
    EXPECT_EQ(stats["devices"][0]["tool"], "finger");
    EXPECT_EQ(stats["devices"][1]["tool"], "knife");
    EXPECT_EQ(stats["devices"][1]["forces"], "forces_2.csv");
    EXPECT_GT(stats["summary"]["cutting_frames"].get<int>(), 0) << "the knife cut while the finger held";
}

TEST_P(EachMethodEndToEnd, TheViewerShowsThreeScenesInAWindow)
{
    if (std::system("command -v xvfb-run > /dev/null 2>&1") != 0) GTEST_SKIP() << "xvfb-run is not installed (scripts/install-deps.sh installs it)";
    for (const char* scene_name : {"cylinder.json", "cylinder_cut.json", "slab_flap_cut_isxfem.json"}) {
        const fs::path d = fresh_dir(std::string("view_") + GetParam() + "_" + fs::path(scene_name).stem().string());
        const std::string command = "xvfb-run -a -s '-screen 0 1280x1024x24' " + quote(VOX_VOXSCULPT_EXE) + " view " +
                                    quote(std::string(VOX_SOURCE_DIR) + "/data/scenes/" + scene_name) + " --solver " + GetParam() +
                                    " --device mouse --size 480x360 --exit-after 1 --screenshot " + quote((d / "view.png").string()) + " > " +
                                    quote((d / "log.txt").string()) + " 2>&1";
        ASSERT_EQ(std::system(command.c_str()), 0) << command << "\n" << slurp(d / "log.txt");
        EXPECT_NE(slurp(d / "log.txt").find(std::string(GetParam()) == "dbg" ? "branched grid" : std::string(GetParam()) == "isxfem" ? "Is-XFEM" : "moved by shape matching"), std::string::npos)
            << slurp(d / "log.txt");
        int w = 0, h = 0, channels = 0;
        std::unique_ptr<unsigned char, void (*)(void*)> data(stbi_load((d / "view.png").c_str(), &w, &h, &channels, 3), stbi_image_free);
        ASSERT_TRUE(data) << scene_name;
        // The object covers a good part of the window: pixels unlike the background's (a corner).
        const unsigned char* corner = data.get() + 3 * (w * (h - 1) + w - 1);
        int object = 0;
        for (int i = 0; i < w * h; ++i) {
            const unsigned char* c = data.get() + 3 * i;
            object += std::abs(c[0] - corner[0]) + std::abs(c[1] - corner[1]) + std::abs(c[2] - corner[2]) > 60;
        }
        EXPECT_GT(object, w * h / 30) << scene_name;
    }
}

TEST_P(EachMethodEndToEnd, TheViewerDrivesTwoToolsByTwoDevicesAtOnce)
{
    // A scripted finger presses the block (its script: down to z = 14.5 by 0.4 s; a 5 mm sphere
    // touches the top, z = 12, at 17) while the mouse holds the knife above it, where it starts.
    if (std::system("command -v xvfb-run > /dev/null 2>&1") != 0) GTEST_SKIP() << "xvfb-run is not installed (scripts/install-deps.sh installs it)";
    const fs::path d = fresh_dir(std::string("view_two_hands_") + GetParam());
    const std::string command = "xvfb-run -a -s '-screen 0 1280x1024x24' " + quote(VOX_VOXSCULPT_EXE) + " view " +
                                quote(std::string(VOX_SOURCE_DIR) + "/data/scenes/two_hands.json") + " --solver " + GetParam() +
                                " --device script --tool finger --device mouse --tool knife --size 480x360 --exit-after 4 --out " +
                                quote(d.string()) + " > " + quote((d / "log.txt").string()) + " 2>&1";
    ASSERT_EQ(std::system(command.c_str()), 0) << command << "\n" << slurp(d / "log.txt");
    const std::string log = slurp(d / "log.txt");
    EXPECT_NE(log.find("tool \"finger\" is driven by: script"), std::string::npos) << log;
    EXPECT_NE(log.find("tool \"knife\" (mouse) ended at (33.50, 12.00, 22.00) mm"), std::string::npos) << log;
    const std::string finger = "tool \"finger\" (script) ended at (";
    const auto at = log.find(finger);
    ASSERT_NE(at, std::string::npos) << log;
    double x = 0, y = 0, z = 0;
    ASSERT_EQ(std::sscanf(log.c_str() + at + finger.size(), "%lf, %lf, %lf", &x, &y, &z), 3) << log;
    EXPECT_NEAR(x, 11.5, 0.05);
    EXPECT_NEAR(y, 11.5, 0.05);
    EXPECT_LT(z, 16.9) << "the finger pressed into the block";
    EXPECT_GE(z, 14.5) << "held on the surface, not through it";
}

INSTANTIATE_TEST_SUITE_P(Methods, EachMethodEndToEnd, ::testing::Values("dbg", "isxfem", "shape_matching"),
                         [](const auto& method) { return std::string(method.param); });
