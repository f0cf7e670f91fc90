// A real brain scan nobody developed against (tests/data/README.md): grey and white matter of
// different stiffness on an oblique 1 mm grid, held at its base, pressed 25 mm by an 8 mm probe,
// then cut by a scalpel, at level 4 (elements 16 voxels a side, many of them nearly empty). Every
// frame converges and the surface moves no further than the tools took it;
// the same run made to diverge stops with exit 2, one line naming the frame, and writes nothing.

#include "app/run_command.hpp"
#include "test_support.hpp"

#include <Eigen/Core>
#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

namespace fs = std::filesystem;
using vox::test::fresh_dir;
using vox::test::quote;
using vox::test::run_voxsculpt;

namespace {
const std::string k_scene = VOX_TEST_DATA_DIR "/brain/brain_press_cut.json";

/// The vertices of an OBJ file, in order.
std::vector<Eigen::Vector3d> obj_vertices(const fs::path& file)
{
    std::vector<Eigen::Vector3d> out;
    std::ifstream in(file);
    for (std::string line; std::getline(in, line);) {
        if (line.rfind("v ", 0) != 0) continue;
        std::istringstream words(line.substr(2));
        Eigen::Vector3d v;
        words >> v.x() >> v.y() >> v.z();
        out.push_back(v);
    }
    return out;
}

/// The bundled scene read as JSON (it has comments), its volume's path made absolute.
nlohmann::json brain_scene()
{
    std::ifstream in(k_scene);
    nlohmann::json scene = nlohmann::json::parse(in, nullptr, true, /*ignore_comments=*/true);
    scene["object"]["volume"] = VOX_TEST_DATA_DIR "/brain/brain_labels.nii.gz";
    return scene;
}
} // namespace

TEST(BrainScan, PressedAndCutEveryFrameConvergesAndNothingMovesBeyondTheTools)
{
    const fs::path d = fresh_dir("brain_press_cut");
    const auto r = run_voxsculpt("run " + quote(k_scene) + " --out " + quote((d / "out").string()));
    ASSERT_EQ(r.exit_code, 0) << r.err;
    std::ifstream in(d / "out" / "stats.json");
    const nlohmann::json stats = nlohmann::json::parse(in);
    const nlohmann::json& summary = stats["summary"];
    EXPECT_EQ(summary["nonconverged_steps"], 0);
    EXPECT_EQ(summary["converged_frames"], summary["frames"]);
    // This run once lost its preconditioner at frame 35 (a contact stiffness lumped negative onto
    // a node outside the material), then ran a node off to 1.9 m and folded elements.
    EXPECT_EQ(summary["preconditioner_fallbacks"], 0);
    EXPECT_EQ(summary["inverted_frames"], 0);
    EXPECT_LT(summary["max_stretch"].get<double>(), 1.5);
    double pushed_n = 0.0;
    for (const nlohmann::json& f : stats["frames"]) {
        EXPECT_TRUE(f["converged"].get<bool>()) << "frame " << f["frame"];
        // The probe pushes 25 mm; the blade cuts without pushing: nothing of the brain moves 40 mm.
        EXPECT_LT(f["max_displacement_mm"].get<double>(), 40.0) << "frame " << f["frame"];
        const nlohmann::json& probe = f["tools"][0]; // the scene's first tool
        if (!probe.is_null())
            pushed_n = std::max(pushed_n, std::hypot(probe["force_n"][0].get<double>(), probe["force_n"][1].get<double>(),
                                                     probe["force_n"][2].get<double>()));
    }
    EXPECT_GT(pushed_n, 1.0);
    EXPECT_GT(summary["separated_faces"].get<long>(), 100) << "the scalpel cut";
    // The surface moves as far as the probe pushed it (25 - 29 mm below where it met it), no
    // further: at the deepest press (frame 80, before the cut changes the surface) against frame 10.
    const std::vector<Eigen::Vector3d> rest = obj_vertices(d / "out" / "frame_00010.obj");
    const std::vector<Eigen::Vector3d> pressed = obj_vertices(d / "out" / "frame_00080.obj");
    ASSERT_EQ(rest.size(), pressed.size());
    double moved_mm = 0.0;
    for (std::size_t i = 0; i < rest.size(); ++i) moved_mm = std::max(moved_mm, (pressed[i] - rest[i]).norm());
    EXPECT_GT(moved_mm, 15.0);
    EXPECT_LT(moved_mm, 40.0);
}

TEST(BrainScan, ARunMadeToDivergeStopsWithExit2AndWritesNothing)
{
    // The same press with steps solved by two CG iterations: the state runs away. One line names
    // the scene, the frame and where; exit 2; no output folder.
    const fs::path d = fresh_dir("brain_diverges");
    nlohmann::json scene = brain_scene();
    scene["solver"] = {{"type", "isxfem"}, {"dt_s", 0.01}, {"cg_max_iterations", 2}, {"preconditioner", "jacobi"}};
    std::ofstream(d / "diverges.json") << scene.dump(2);
    const auto r = run_voxsculpt("run " + quote((d / "diverges.json").string()) + " --frames 120 --out " + quote((d / "out").string()));
    EXPECT_EQ(r.exit_code, 2) << r.err;
    EXPECT_NE(r.err.find("diverges.json: the simulation diverged at frame "), std::string::npos) << r.err;
    EXPECT_FALSE(fs::exists(d / "out"));
}
