#include "io/scene.hpp"

#include "test_support.hpp"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <array>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <cmath>
#include <iterator>
#include <limits>
#include <set>
#include <string>
#include <utility>
#include <vector>

namespace {

namespace fs = std::filesystem;
using nlohmann::json;
using vox::test::error_of;
using namespace vox::io;

const fs::path source_dir = VOX_SOURCE_DIR;
const fs::path scenes_dir = source_dir / "data" / "scenes";
const fs::path bad_dir = fs::path(VOX_TEST_DATA_DIR) / "bad";

json read_json(const fs::path& path)
{
    std::ifstream in(path);
    return json::parse(in);
}

/// Writes `text` to a file in the test's temporary folder and returns its path.
fs::path write_temp(const std::string& name, const std::string& text)
{
    const fs::path path = fs::path(testing::TempDir()) / name;
    std::ofstream(path) << text;
    return path;
}

/// The smallest valid scene: a beam phantom and nothing else.
json minimal_scene()
{
    return json::parse(R"({"object": {"phantom": {"shape": "beam"}}})");
}

// ---------------------------------------------------------------------------------------------
// The example scenes.
// ---------------------------------------------------------------------------------------------

TEST(SceneExamples, EveryExampleSceneLoads)
{
    std::set<std::string> names;
    for (const fs::directory_entry& entry : fs::directory_iterator(scenes_dir)) {
        if (entry.path().extension() == ".json") {
            SCOPED_TRACE(entry.path().string());
            EXPECT_NO_THROW(static_cast<void>(load_scene(entry.path())));
            names.insert(entry.path().filename().string());
        }
    }
    for (const char* name : {"liver.json", "beam.json", "elephant.json", "cylinder.json"}) {
        EXPECT_TRUE(names.count(name)) << name;
    }
}

TEST(SceneExamples, Liver)
{
    const Scene s = load_scene(scenes_dir / "liver.json");
    EXPECT_EQ(s.source, (scenes_dir / "liver.json").string());
    EXPECT_EQ(s.folder, scenes_dir);
    EXPECT_EQ(s.object.kind, ObjectKind::volume);
    EXPECT_EQ(s.object.file, source_dir / "data" / "liver.inr.gz");
    EXPECT_EQ(s.object.select.labels, (std::vector<std::int32_t>{255, 127}));
    EXPECT_FALSE(s.object.select.threshold_min);
    EXPECT_EQ(s.object.levels, 3);

    EXPECT_EQ(s.default_material.youngs_modulus_pa, 3e4);
    EXPECT_EQ(s.default_material.density_kg_m3, 1060.0);
    ASSERT_EQ(s.label_materials.size(), 1u);
    // Label 127 sets only E; nu and rho come from the scene's default material.
    EXPECT_EQ(s.material(127).youngs_modulus_pa, 1e5);
    EXPECT_EQ(s.material(127).poisson_ratio, 0.45);
    EXPECT_EQ(s.material(127).density_kg_m3, 1060.0);
    EXPECT_EQ(&s.material(255), &s.default_material);

    EXPECT_EQ(s.gravity_m_s2, Eigen::Vector3d(0, 9.81, 0));
    ASSERT_EQ(s.tools.size(), 2u);
    EXPECT_EQ(s.tools[0].shape, ToolShape::sphere);
    EXPECT_EQ(s.tools[0].radius_mm, 5.0);
    EXPECT_EQ(s.tools[1].shape, ToolShape::scalpel);
    EXPECT_EQ(s.tools[0].action, ToolAction::push); // the shapes' default actions
    EXPECT_EQ(s.tools[1].action, ToolAction::cut);
    ASSERT_EQ(s.script.size(), 5u);
    EXPECT_EQ(s.script[0].orientation.coeffs(), Eigen::Quaterniond::Identity().coeffs());
    EXPECT_EQ(s.script[2].t_s, s.script[3].t_s); // equal times are allowed
    EXPECT_EQ(s.script[3].tool, "scalpel");
    EXPECT_EQ(s.script[3].tool_index, 1u);
    EXPECT_EQ(s.output.dir, scenes_dir / "out" / "liver");
}

TEST(SceneExamples, Beam)
{
    const Scene s = load_scene(scenes_dir / "beam.json");
    EXPECT_EQ(s.object.kind, ObjectKind::phantom);
    EXPECT_EQ(s.object.phantom.shape, vox::grid::PhantomShape::beam);
    EXPECT_EQ(s.object.phantom.size_mm, Eigen::Vector3d(200, 10, 10));
    EXPECT_EQ(s.object.phantom.voxel_mm, 1.0);
    EXPECT_EQ(s.object.levels, 1);
    EXPECT_EQ(s.solver.type, SolverType::dbg);
    ASSERT_EQ(s.constraints.size(), 1u);
    EXPECT_EQ(s.constraints[0].type, ConstraintType::fixed);
    EXPECT_EQ(s.constraints[0].box_min_mm, Eigen::Vector3d(0, 0, 0));
    EXPECT_EQ(s.constraints[0].box_max_mm, Eigen::Vector3d(5, 10, 10));
    EXPECT_EQ(s.constraints[0].held_axes, (std::array<bool, 3>{true, true, true}));
    ASSERT_EQ(s.tools.size(), 1u);
    EXPECT_EQ(s.tools[0].name, "blade");
    EXPECT_EQ(s.tools[0].shape, ToolShape::blade);
    EXPECT_EQ(s.tools[0].size_mm, Eigen::Vector3d(40, 1, 20));
    ASSERT_EQ(s.script.size(), 2u);
    EXPECT_EQ(s.script[1].t_s, 1.0);
    EXPECT_EQ(s.script[1].position_mm, Eigen::Vector3d(100, 5, -10));
    EXPECT_EQ(s.output.mesh_every_n_frames, 10);
}

TEST(SceneExamples, Elephant)
{
    const Scene s = load_scene(scenes_dir / "elephant.json");
    EXPECT_EQ(s.object.kind, ObjectKind::mesh);
    EXPECT_EQ(s.object.file, source_dir / "data" / "elephant.off");
    EXPECT_EQ(s.object.scale_mm_per_unit, 100.0);
    EXPECT_EQ(s.object.voxel_mm, 1.0);
    EXPECT_EQ(s.gravity_m_s2, Eigen::Vector3d(0, -9.81, 0));
    ASSERT_EQ(s.tools.size(), 2u);
    EXPECT_EQ(s.tools[0].shape, ToolShape::scalpel);
    EXPECT_EQ(s.tools[0].size_mm, Eigen::Vector3d(30, 0.5, 8)); // the documented default
    EXPECT_EQ(s.tools[1].shape, ToolShape::mesh);
    EXPECT_EQ(s.tools[1].mesh, source_dir / "data" / "sphere.off");
}

TEST(SceneExamples, Cylinder)
{
    const Scene s = load_scene(scenes_dir / "cylinder.json");
    EXPECT_EQ(s.object.phantom.shape, vox::grid::PhantomShape::cylinder);
    EXPECT_EQ(s.object.phantom.radius_mm, 5.0);
    EXPECT_EQ(s.object.phantom.length_mm, 60.0);
    EXPECT_EQ(s.object.phantom.voxel_mm, 0.5);
    EXPECT_EQ(s.solver.dt_s, 0.005);
    EXPECT_EQ(s.solver.cg_max_iterations, 200); // absent: default
    ASSERT_EQ(s.constraints.size(), 2u);
    EXPECT_EQ(s.constraints[0].type, ConstraintType::fixed);
    EXPECT_EQ(s.constraints[0].held_axes, (std::array<bool, 3>{true, true, true}));
    // The roller at the far end holds the rod across (y, z) and leaves it free along its axis.
    EXPECT_EQ(s.constraints[1].type, ConstraintType::slide);
    EXPECT_EQ(s.constraints[1].held_axes, (std::array<bool, 3>{false, true, true}));
}

TEST(SceneExamples, TheFormatPageShowsTheExampleScenesAsTheyAre)
{
    // docs/scene-format.md shows each example under a heading naming its file; a scene edited
    // without its page (or the reverse) fails here.
    std::ifstream in(source_dir / "docs" / "scene-format.md");
    const std::string page((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    for (const char* name : {"liver.json", "beam.json", "elephant.json", "cylinder.json"}) {
        SCOPED_TRACE(name);
        const std::string title = std::string("`").append(name).append("`\n");
        const std::size_t heading = page.find(title);
        ASSERT_NE(heading, std::string::npos);
        const std::size_t begin = page.find("```json\n", heading);
        ASSERT_NE(begin, std::string::npos);
        const std::size_t end = page.find("```\n", begin + 8);
        ASSERT_NE(end, std::string::npos);
        EXPECT_EQ(json::parse(page.substr(begin + 8, end - begin - 8)), read_json(scenes_dir / name));
    }
}

// ---------------------------------------------------------------------------------------------
// Defaults.
// ---------------------------------------------------------------------------------------------

TEST(SceneDefaults, AbsentKeysTakeTheDocumentedDefaults)
{
    const Scene s = parse_scene(minimal_scene(), "/tmp/scenes", "minimal.json");
    EXPECT_EQ(s.object.phantom.shape, vox::grid::PhantomShape::beam);
    EXPECT_EQ(s.object.phantom.size_mm, Eigen::Vector3d(200, 10, 10));
    EXPECT_EQ(s.object.phantom.voxel_mm, 1.0);
    EXPECT_EQ(s.object.levels, 3);
    EXPECT_EQ(s.default_material.youngs_modulus_pa, 3e4);
    EXPECT_EQ(s.default_material.poisson_ratio, 0.45);
    EXPECT_EQ(s.default_material.density_kg_m3, 1000.0);
    EXPECT_TRUE(s.label_materials.empty());
    EXPECT_EQ(s.solver.type, SolverType::dbg);
    EXPECT_EQ(s.solver.dt_s, 0.01);
    EXPECT_EQ(s.solver.cg_tolerance, 1e-6);
    EXPECT_EQ(s.solver.cg_max_iterations, 200);
    EXPECT_EQ(s.solver.mode, SolverMode::dynamic);
    EXPECT_EQ(s.solver.rayleigh_mass_per_s, 0.5);
    EXPECT_EQ(s.solver.rayleigh_stiffness_s, 0.002);
    EXPECT_EQ(s.solver.newton_max_iterations, 30);
    EXPECT_EQ(s.gravity_m_s2, Eigen::Vector3d(0, 0, -9.81));
    EXPECT_TRUE(s.constraints.empty());
    EXPECT_TRUE(s.loads.empty());
    EXPECT_TRUE(s.tools.empty());
    EXPECT_TRUE(s.script.empty());
    EXPECT_EQ(s.output.dir, fs::path("/tmp/scenes/out"));
    EXPECT_EQ(s.output.mesh_every_n_frames, 10);
}

TEST(SceneDefaults, EmptySectionsTakeTheDefaultsToo)
{
    json doc = minimal_scene();
    doc["materials"] = json::object();
    doc["materials"]["default"] = json::object();
    doc["solver"] = json::object();
    doc["output"] = json::object();
    doc["loads"] = json::array();
    const Scene s = parse_scene(doc, "/tmp/scenes", "empty-sections.json");
    EXPECT_EQ(s.default_material.poisson_ratio, 0.45);
    EXPECT_EQ(s.solver.dt_s, 0.01);
    EXPECT_EQ(s.solver.mode, SolverMode::dynamic);
    EXPECT_EQ(s.solver.rayleigh_mass_per_s, 0.5);
    EXPECT_EQ(s.solver.rayleigh_stiffness_s, 0.002);
    EXPECT_EQ(s.solver.newton_max_iterations, 30);
    EXPECT_TRUE(s.loads.empty());
    EXPECT_EQ(s.output.dir, fs::path("/tmp/scenes/out"));
}

TEST(SceneDefaults, EachPhantomShapeHasItsOwnDefaults)
{
    const auto phantom = [](const char* shape) {
        json doc = minimal_scene();
        doc["object"]["phantom"]["shape"] = shape;
        return parse_scene(doc, "/tmp", "phantom.json").object.phantom;
    };
    EXPECT_EQ(phantom("beam").size_mm, Eigen::Vector3d(200, 10, 10));
    EXPECT_EQ(phantom("block").size_mm, Eigen::Vector3d(20, 20, 20));
    EXPECT_EQ(phantom("sphere").radius_mm, 10.0);
    EXPECT_EQ(phantom("cylinder").radius_mm, 5.0);
    EXPECT_EQ(phantom("cylinder").length_mm, 60.0);
    const vox::grid::PhantomSpec u = phantom("utube");
    EXPECT_EQ(u.leg_mm, 3.0);
    EXPECT_EQ(u.gap_mm, 2.0);
    EXPECT_EQ(u.height_mm, 16.0);
    EXPECT_EQ(u.depth_mm, 3.0);
    EXPECT_EQ(u.voxel_mm, 1.0);
}

// ---------------------------------------------------------------------------------------------
// Accepted forms.
// ---------------------------------------------------------------------------------------------

/// A volume object selecting with `select` (the liver scan, so the file exists).
json volume_scene(const json& select)
{
    return json{{"object", {{"volume", "../liver.inr.gz"}, {"select", select}, {"levels", 3}}}};
}

TEST(SceneParse, ThresholdWithOneNumberHasNoUpperBound)
{
    const Scene s = parse_scene(volume_scene({{"threshold", 226}}), scenes_dir, "t.json");
    EXPECT_TRUE(s.object.select.labels.empty());
    EXPECT_EQ(s.object.select.threshold_min, 226.0);
    EXPECT_FALSE(s.object.select.threshold_max);
}

TEST(SceneParse, ThresholdPairIsInclusiveAndMayBeOneValue)
{
    const Scene s = parse_scene(volume_scene({{"threshold", {226, 3071}}}), scenes_dir, "t.json");
    EXPECT_EQ(s.object.select.threshold_min, 226.0);
    EXPECT_EQ(s.object.select.threshold_max, 3071.0);
    const Scene one = parse_scene(volume_scene({{"threshold", {255, 255}}}), scenes_dir, "t.json");
    EXPECT_EQ(one.object.select.threshold_max, 255.0);
}

TEST(SceneParse, SingleLabelMayOmitTheBrackets)
{
    const Scene s = parse_scene(volume_scene({{"label", 255}}), scenes_dir, "l.json");
    EXPECT_EQ(s.object.select.labels, std::vector<std::int32_t>{255});
}

TEST(SceneParse, ScanWithoutSelectionKeepsEveryLabel)
{
    json doc = json::parse(R"({
        "object": {"volume": "../liver.inr.gz", "levels": 3},
        "materials": {"labels": {"85": {"density_kg_m3": 1100}}}
    })");
    const Scene s = parse_scene(doc, scenes_dir, "whole.json");
    EXPECT_TRUE(s.object.select.empty());
    // Any label is accepted here; the scan is checked against it once read.
    EXPECT_EQ(s.material(85).density_kg_m3, 1100.0);
}

TEST(SceneParse, MeshVoxelSizeIsOptional)
{
    const json doc = json::parse(R"({"object": {"mesh": "../sphere.off", "levels": 0}})");
    const Scene s = parse_scene(doc, scenes_dir, "mesh.json");
    EXPECT_FALSE(s.object.voxel_mm);
    EXPECT_EQ(s.object.scale_mm_per_unit, 1.0);
}

TEST(SceneParse, LevelsRangeFromZeroToSix)
{
    json doc = minimal_scene();
    for (const int level : {0, 6}) {
        doc["object"]["levels"] = level;
        EXPECT_EQ(parse_scene(doc, "/tmp", "l.json").object.levels, level);
    }
    doc["object"]["levels"] = -1;
    EXPECT_EQ(error_of([&] { static_cast<void>(parse_scene(doc, "/tmp", "l.json")); }),
              "l.json: object.levels: must be in [0, 6], got -1");
}

TEST(SceneParse, IsxfemIsAcceptedByTheReader)
{
    json doc = minimal_scene();
    doc["solver"] = {{"type", "isxfem"}};
    EXPECT_EQ(parse_scene(doc, "/tmp", "x.json").solver.type, SolverType::isxfem);
}

TEST(SceneDefaults, StructDefaultsMatchTheReader)
{
    // Code that builds settings without a file (tests, the solver) gets the documented defaults.
    const SolverSettings solver;
    EXPECT_EQ(solver.mode, SolverMode::dynamic);
    EXPECT_EQ(solver.rayleigh_mass_per_s, 0.5);
    EXPECT_EQ(solver.rayleigh_stiffness_s, 0.002);
    EXPECT_EQ(solver.newton_max_iterations, 30);
    const Constraint constraint; // type fixed: holds every axis
    EXPECT_EQ(constraint.type, ConstraintType::fixed);
    EXPECT_EQ(constraint.held_axes, (std::array<bool, 3>{true, true, true}));
}

/// parse_scene's message for `doc` ("FILE: key.path: problem"), or "" when it is accepted.
std::string scene_error(const json& doc)
{
    return error_of([&] { static_cast<void>(parse_scene(doc, "/tmp", "s.json")); });
}

TEST(SceneParse, SolverModeAndNewKeys)
{
    json doc = minimal_scene();
    doc["solver"] = json::parse(R"({"mode": "static", "rayleigh_mass_per_s": 2, "rayleigh_stiffness_s": 0.01,
                                    "newton_max_iterations": 35})");
    const Scene s = parse_scene(doc, "/tmp", "solver.json");
    EXPECT_EQ(s.solver.mode, SolverMode::static_equilibrium);
    EXPECT_EQ(s.solver.rayleigh_mass_per_s, 2.0);
    EXPECT_EQ(s.solver.rayleigh_stiffness_s, 0.01);
    EXPECT_EQ(s.solver.newton_max_iterations, 35);
    EXPECT_EQ(s.solver.dt_s, 0.01); // untouched keys keep their defaults

    doc["solver"] = {{"mode", "dynamic"}};
    EXPECT_EQ(parse_scene(doc, "/tmp", "solver.json").solver.mode, SolverMode::dynamic);

    // Zero damping is allowed (undamped dynamics), and one Newton iteration.
    doc["solver"] = {{"rayleigh_mass_per_s", 0}, {"rayleigh_stiffness_s", 0.0}, {"newton_max_iterations", 1}};
    const Scene undamped = parse_scene(doc, "/tmp", "solver.json");
    EXPECT_EQ(undamped.solver.rayleigh_mass_per_s, 0.0);
    EXPECT_EQ(undamped.solver.rayleigh_stiffness_s, 0.0);
    EXPECT_EQ(undamped.solver.newton_max_iterations, 1);
}

TEST(SceneParse, SolverNewKeysOutOfRange)
{
    json doc = minimal_scene();
    doc["solver"] = {{"mode", "quasistatic"}};
    EXPECT_EQ(scene_error(doc), "s.json: solver.mode: expected one of \"dynamic\", \"static\", got \"quasistatic\"");
    doc["solver"] = {{"mode", 1}};
    EXPECT_EQ(scene_error(doc), "s.json: solver.mode: expected a string, got 1");
    doc["solver"] = {{"rayleigh_mass_per_s", -0.5}};
    EXPECT_EQ(scene_error(doc), "s.json: solver.rayleigh_mass_per_s: must be >= 0, got -0.5");
    doc["solver"] = {{"rayleigh_stiffness_s", -1e-3}};
    EXPECT_EQ(scene_error(doc), "s.json: solver.rayleigh_stiffness_s: must be >= 0, got -0.001");
    doc["solver"] = {{"newton_max_iterations", 0}};
    EXPECT_EQ(scene_error(doc), "s.json: solver.newton_max_iterations: must be >= 1, got 0");
    doc["solver"] = {{"newton_max_iterations", 2.5}};
    EXPECT_EQ(scene_error(doc), "s.json: solver.newton_max_iterations: expected an integer, got 2.5");
}

TEST(SceneParse, SlideHoldsTheListedAxes)
{
    json doc = minimal_scene();
    doc["constraints"] = json::parse(R"([
        {"type": "slide", "axes": ["x"], "box_mm": [[-1, -1, -1], [0, 11, 11]]},
        {"type": "slide", "axes": ["z", "y"], "box_mm": [[199, -1, -1], [200, 11, 11]]},
        {"type": "fixed", "box_mm": [[0, 0, 0], [0, 0, 0]]}
    ])");
    const Scene s = parse_scene(doc, "/tmp", "slide.json");
    ASSERT_EQ(s.constraints.size(), 3u);
    // A symmetry plane x = const holds x; a roller along x holds y and z.
    EXPECT_EQ(s.constraints[0].held_axes, (std::array<bool, 3>{true, false, false}));
    EXPECT_EQ(s.constraints[1].held_axes, (std::array<bool, 3>{false, true, true}));
    EXPECT_EQ(s.constraints[1].box_min_mm, Eigen::Vector3d(199, -1, -1));
    EXPECT_EQ(s.constraints[2].held_axes, (std::array<bool, 3>{true, true, true}));
    EXPECT_EQ(s.constraints[2].box_max_mm, Eigen::Vector3d(0, 0, 0)); // a point box is allowed

    doc["constraints"] = json::parse(R"([{"type": "slide", "axes": [], "box_mm": [[0, 0, 0], [1, 1, 1]]}])");
    EXPECT_EQ(scene_error(doc), "s.json: constraints[0].axes: lists no axis; such a constraint holds nothing");
    doc["constraints"][0]["axes"] = {"x", "y", "z"};
    EXPECT_EQ(scene_error(doc),
              "s.json: constraints[0].axes: lists every axis; that is a fixed constraint (\"type\": \"fixed\")");
    doc["constraints"][0]["axes"] = {"y", "y"};
    EXPECT_EQ(scene_error(doc), "s.json: constraints[0].axes[1]: axis y is listed twice");
    doc["constraints"][0].erase("axes");
    EXPECT_EQ(scene_error(doc), "s.json: constraints[0].axes: required key is missing");
}

TEST(SceneParse, Loads)
{
    json doc = minimal_scene();
    doc["loads"] = json::parse(R"([
        {"box_mm": [[199, -1, -1], [200, 11, 11]], "force_n": [0, 0, -0.01]},
        {"force_n": [1.5, -2, 3e-3], "box_mm": [[10, 5, 5], [10, 5, 5]]}
    ])");
    const Scene s = parse_scene(doc, "/tmp", "loads.json");
    ASSERT_EQ(s.loads.size(), 2u);
    EXPECT_EQ(s.loads[0].box_min_mm, Eigen::Vector3d(199, -1, -1));
    EXPECT_EQ(s.loads[0].box_max_mm, Eigen::Vector3d(200, 11, 11));
    EXPECT_EQ(s.loads[0].force_n, Eigen::Vector3d(0, 0, -0.01));
    EXPECT_EQ(s.loads[1].box_min_mm, s.loads[1].box_max_mm); // a point box is allowed
    EXPECT_EQ(s.loads[1].force_n, Eigen::Vector3d(1.5, -2, 3e-3));
    EXPECT_EQ(s.gravity_m_s2, Eigen::Vector3d(0, 0, -9.81)); // loads come on top of gravity
}

TEST(SceneParse, BadLoads)
{
    json doc = minimal_scene();
    const auto with_load = [&](const char* load) {
        doc["loads"] = json::array({json::parse(load)});
        return scene_error(doc);
    };
    EXPECT_EQ(with_load(R"({"box_mm": [[0, 0, 0], [1, 1, 1]]})"), "s.json: loads[0].force_n: required key is missing");
    EXPECT_EQ(with_load(R"({"force_n": [0, 0, 1]})"), "s.json: loads[0].box_mm: required key is missing");
    EXPECT_EQ(with_load(R"({"box_mm": [[0, 0, 2], [1, 1, 1]], "force_n": [0, 0, 1]})"),
              "s.json: loads[0].box_mm: min corner is above max corner along z (2 > 1)");
    EXPECT_EQ(with_load(R"({"box_mm": [[0, 0, 0], [1, 1, 1]], "force_n": [0, 1]})"),
              "s.json: loads[0].force_n: expected an array of 3 numbers, got [0,1]");
    EXPECT_EQ(with_load(R"({"box_mm": [[0, 0, 0], [1, 1, 1]], "force_n": [0, "1", 0]})"),
              "s.json: loads[0].force_n[1]: expected a number, got \"1\"");
    EXPECT_EQ(with_load(R"({"box_mm": [0, 0, 0], "force_n": [0, 0, 1]})"),
              "s.json: loads[0].box_mm: expected [[x, y, z], [x, y, z]] (the box's min and max corners), got [0,0,0]");
    EXPECT_EQ(with_load(R"({"box_mm": [[0, 0, 0], [1, 1, 1]], "force_n": [0, 0, 1], "force_mm": [0, 0, 1]})")
                  .rfind("s.json: loads[0].force_mm: unknown key (known keys: box_mm, force_n)", 0),
              0u);
    doc["loads"] = json::object();
    EXPECT_EQ(scene_error(doc), "s.json: loads: expected an array, got {}");

    // A JSON file cannot hold NaN or infinity; a document built in code can, and is refused.
    doc["loads"] = json::array({{{"box_mm", {{0, 0, 0}, {1, 1, 1}}}, {"force_n", {0.0, std::nan(""), 0.0}}}});
    EXPECT_EQ(scene_error(doc), "s.json: loads[0].force_n[1]: must be a finite number");
    doc["loads"] = json::array(
        {{{"box_mm", {{0, 0, -std::numeric_limits<double>::infinity()}, {1, 1, 1}}}, {"force_n", {0, 0, 1}}}});
    EXPECT_EQ(scene_error(doc), "s.json: loads[0].box_mm[0][2]: must be a finite number");
}

TEST(SceneParse, Obstacles)
{
    json doc = minimal_scene();
    const fs::path mesh = write_temp("obstacle.off", "OFF\n4 4 0\n0 0 0\n1 0 0\n0 1 0\n0 0 1\n3 0 2 1\n3 0 1 3\n3 0 3 2\n3 1 2 3\n");
    doc["obstacles"] = json::array({
        {{"shape", "plane"}, {"point_mm", {0, 0, -5}}, {"normal", {0, 0, 2}}},
        {{"shape", "box"}, {"box_mm", {{-10, -10, -20}, {10, 30, -0.5}}}, {"friction", 0.8}, {"stiffness_n_per_mm", 50}},
        {{"shape", "mesh"}, {"mesh", mesh.string()}, {"position_mm", {1, 2, 3}}, {"orientation_wxyz", {0, 0, 0, 2}}, {"scale", 10}},
    });
    const Scene s = parse_scene(doc, "/tmp", "obstacles.json");
    ASSERT_EQ(s.obstacles.size(), 3u);
    EXPECT_EQ(s.obstacles[0].shape, ObstacleShape::plane);
    EXPECT_EQ(s.obstacles[0].point_mm, Eigen::Vector3d(0, 0, -5));
    EXPECT_EQ(s.obstacles[0].normal, Eigen::Vector3d(0, 0, 1)); // normalised
    EXPECT_EQ(s.obstacles[0].friction, 0.3);                     // the documented defaults
    EXPECT_EQ(s.obstacles[0].stiffness_n_per_mm, 10.0);
    EXPECT_EQ(s.obstacles[1].shape, ObstacleShape::box);
    EXPECT_EQ(s.obstacles[1].box_max_mm, Eigen::Vector3d(10, 30, -0.5));
    EXPECT_EQ(s.obstacles[1].friction, 0.8);
    EXPECT_EQ(s.obstacles[1].stiffness_n_per_mm, 50.0);
    EXPECT_EQ(s.obstacles[2].shape, ObstacleShape::mesh);
    EXPECT_EQ(s.obstacles[2].mesh, mesh);
    EXPECT_EQ(s.obstacles[2].position_mm, Eigen::Vector3d(1, 2, 3));
    EXPECT_EQ(s.obstacles[2].orientation.coeffs(), Eigen::Quaterniond(0, 0, 0, 1).coeffs());
    EXPECT_EQ(s.obstacles[2].scale, 10.0);
    // Something to rest on: the object falls onto it, unless the file says what its pieces do.
    EXPECT_EQ(s.object.unheld, UnheldPieces::fall);
    doc["object"]["unheld_pieces"] = "hold";
    EXPECT_EQ(parse_scene(doc, "/tmp", "obstacles.json").object.unheld, UnheldPieces::hold);
    EXPECT_EQ(parse_scene(minimal_scene(), "/tmp", "none.json").object.unheld, UnheldPieces::hold);
}

TEST(SceneParse, BadObstaclesNameTheKeyPath)
{
    json doc = minimal_scene();
    const auto with = [&](const char* obstacle) {
        doc["obstacles"] = json::array({json::parse(obstacle)});
        return scene_error(doc);
    };
    EXPECT_EQ(with(R"({"shape": "cone"})"), "s.json: obstacles[0].shape: expected one of \"plane\", \"box\", \"mesh\", got \"cone\"");
    EXPECT_EQ(with(R"({"shape": "plane", "point_mm": [0, 0, 0]})"), "s.json: obstacles[0].normal: required key is missing");
    EXPECT_EQ(with(R"({"shape": "plane", "point_mm": [0, 0, 0], "normal": [0, 0, 0]})"),
              "s.json: obstacles[0].normal: has no direction (its length is below 1e-9)");
    EXPECT_EQ(with(R"({"shape": "box", "box_mm": [[0, 0, 0], [1, 0, 1]]})"),
              "s.json: obstacles[0].box_mm: is flat (an obstacle box needs a thickness on every axis)");
    EXPECT_EQ(with(R"({"shape": "box", "box_mm": [[0, 0, 0], [1, 1, 1]], "friction": -0.1})").rfind("s.json: obstacles[0].friction: ", 0), 0u);
    EXPECT_EQ(with(R"({"shape": "box", "box_mm": [[0, 0, 0], [1, 1, 1]], "stiffness_n_per_mm": 0})").rfind("s.json: obstacles[0].stiffness_n_per_mm: ", 0), 0u);
    EXPECT_EQ(with(R"({"shape": "mesh", "mesh": "no_such_table.stl"})").rfind("s.json: obstacles[0].mesh: ", 0), 0u);
    EXPECT_EQ(with(R"({"shape": "box", "box_mm": [[0, 0, 0], [1, 1, 1]], "normal": [0, 0, 1]})")
                  .rfind("s.json: obstacles[0].normal: unknown key", 0), 0u);
}

TEST(SceneParse, PieceContactIsOffUnlessTurnedOnAndTakesAStiffness)
{
    json doc = minimal_scene();
    EXPECT_FALSE(parse_scene(doc, "/tmp", "p.json").piece_contact.enabled);
    doc["piece_contact"] = true;
    EXPECT_TRUE(parse_scene(doc, "/tmp", "p.json").piece_contact.enabled);
    EXPECT_EQ(parse_scene(doc, "/tmp", "p.json").piece_contact.stiffness_n_per_mm, 10.0);
    doc["piece_contact"] = {{"stiffness_n_per_mm", 25}};
    const Scene s = parse_scene(doc, "/tmp", "p.json");
    EXPECT_TRUE(s.piece_contact.enabled);
    EXPECT_EQ(s.piece_contact.stiffness_n_per_mm, 25.0);
    doc["piece_contact"] = false;
    EXPECT_FALSE(parse_scene(doc, "/tmp", "p.json").piece_contact.enabled);
    doc["piece_contact"] = {{"stiffness_n_per_mm", 0}};
    EXPECT_EQ(scene_error(doc).rfind("s.json: piece_contact.stiffness_n_per_mm: ", 0), 0u);
    doc["piece_contact"] = {{"friction", 0.3}};
    EXPECT_EQ(scene_error(doc).rfind("s.json: piece_contact.friction: unknown key", 0), 0u);
    doc["piece_contact"] = "yes";
    EXPECT_EQ(scene_error(doc), "s.json: piece_contact: must be true, false or an object with \"stiffness_n_per_mm\"");
}

// ---------------------------------------------------------------------------------------------
// Tools: contact and cutting keys; script: orientation.
// ---------------------------------------------------------------------------------------------

/// The minimal scene with `tools` (and a script when given).
json scene_with_tools(const json& tools, const json& script = json())
{
    json doc = minimal_scene();
    doc["tools"] = tools;
    if (!script.is_null()) {
        doc["script"] = script;
    }
    return doc;
}

TEST(SceneDefaults, ToolContactKeysTakeTheDocumentedDefaults)
{
    const json tools = json::parse(R"([
        {"name": "b", "shape": "blade", "size_mm": [40, 1, 20]},
        {"name": "s", "shape": "scalpel"},
        {"name": "p", "shape": "sphere", "radius_mm": 5},
        {"name": "m", "shape": "mesh", "mesh": "../sphere.off"}
    ])");
    const Scene s = parse_scene(scene_with_tools(tools), scenes_dir, "tools.json");
    ASSERT_EQ(s.tools.size(), 4u);
    // Blades and scalpels cut; spheres and meshes push.
    EXPECT_EQ(s.tools[0].action, ToolAction::cut);
    EXPECT_EQ(s.tools[1].action, ToolAction::cut);
    EXPECT_EQ(s.tools[2].action, ToolAction::push);
    EXPECT_EQ(s.tools[3].action, ToolAction::push);
    for (const ToolSpec& t : s.tools) {
        SCOPED_TRACE(t.name);
        EXPECT_EQ(t.action, default_tool_action(t.shape));
        EXPECT_EQ(t.cut_mode, CutMode::remove);
        EXPECT_EQ(t.push_margin_mm, 1.0);
        EXPECT_EQ(t.contact_stiffness_n_per_mm, 5.0);
        EXPECT_EQ(t.cut_pressure_pa, 2e4);
        EXPECT_EQ(t.wet_rate_per_s, 1.0);
    }

    // Code that builds a ToolSpec without a file gets the same defaults (for the default shape).
    const ToolSpec spec;
    EXPECT_EQ(spec.shape, ToolShape::blade);
    EXPECT_EQ(spec.action, ToolAction::cut);
    EXPECT_EQ(spec.cut_mode, CutMode::remove);
    EXPECT_EQ(spec.push_margin_mm, 1.0);
    EXPECT_EQ(spec.contact_stiffness_n_per_mm, 5.0);
    EXPECT_EQ(spec.cut_pressure_pa, 2e4);
    EXPECT_EQ(spec.wet_rate_per_s, 1.0);
    EXPECT_EQ(default_tool_action(ToolShape::blade), ToolAction::cut);
    EXPECT_EQ(default_tool_action(ToolShape::scalpel), ToolAction::cut);
    EXPECT_EQ(default_tool_action(ToolShape::sphere), ToolAction::push);
    EXPECT_EQ(default_tool_action(ToolShape::mesh), ToolAction::push);
}

TEST(SceneParse, ToolContactKeysAreRead)
{
    const json tools = json::parse(R"([
        {"name": "blade", "shape": "blade", "size_mm": [40, 1, 20], "action": "cut", "cut_mode": "separate",
         "push_margin_mm": 0.5, "contact_stiffness_n_per_mm": 12.5, "cut_pressure_pa": 3e5, "wet_rate_per_s": 0.25},
        {"name": "sponge", "shape": "sphere", "radius_mm": 4, "action": "wet", "wet_rate_per_s": 2},
        {"name": "flat", "shape": "scalpel", "action": "push", "push_margin_mm": 0},
        {"name": "gouge", "shape": "sphere", "radius_mm": 2, "action": "cut", "cut_mode": "remove",
         "push_margin_mm": 100, "contact_stiffness_n_per_mm": 1e4, "cut_pressure_pa": 1e9, "wet_rate_per_s": 1e3}
    ])");
    const Scene s = parse_scene(scene_with_tools(tools), "/tmp", "tools.json");
    ASSERT_EQ(s.tools.size(), 4u);
    const ToolSpec& blade = s.tools[0];
    EXPECT_EQ(blade.action, ToolAction::cut);
    EXPECT_EQ(blade.cut_mode, CutMode::separate);
    EXPECT_EQ(blade.push_margin_mm, 0.5);
    EXPECT_EQ(blade.contact_stiffness_n_per_mm, 12.5);
    EXPECT_EQ(blade.cut_pressure_pa, 3e5);
    EXPECT_EQ(blade.wet_rate_per_s, 0.25); // does not apply to a cut tool: accepted all the same
    EXPECT_EQ(blade.size_mm, Eigen::Vector3d(40, 1, 20));

    const ToolSpec& sponge = s.tools[1];
    EXPECT_EQ(sponge.action, ToolAction::wet);
    EXPECT_EQ(sponge.wet_rate_per_s, 2.0);
    EXPECT_EQ(sponge.cut_pressure_pa, 2e4); // untouched keys keep their defaults
    EXPECT_EQ(sponge.radius_mm, 4.0);

    // A scalpel may be made a pusher, a sphere a cutter; the range ends are included.
    EXPECT_EQ(s.tools[2].action, ToolAction::push);
    EXPECT_EQ(s.tools[2].push_margin_mm, 0.0);
    const ToolSpec& gouge = s.tools[3];
    EXPECT_EQ(gouge.action, ToolAction::cut);
    EXPECT_EQ(gouge.cut_mode, CutMode::remove);
    EXPECT_EQ(gouge.push_margin_mm, 100.0);
    EXPECT_EQ(gouge.contact_stiffness_n_per_mm, 1e4);
    EXPECT_EQ(gouge.cut_pressure_pa, 1e9);
    EXPECT_EQ(gouge.wet_rate_per_s, 1e3);
}

TEST(SceneParse, ToolKeysThatDoNotApplyToTheActionAreAccepted)
{
    const json tools = json::parse(R"([
        {"name": "probe", "shape": "sphere", "radius_mm": 5, "action": "push", "cut_mode": "separate",
         "cut_pressure_pa": 1e3, "wet_rate_per_s": 5}
    ])");
    const Scene s = parse_scene(scene_with_tools(tools), "/tmp", "tools.json");
    EXPECT_EQ(s.tools[0].action, ToolAction::push);
    EXPECT_EQ(s.tools[0].cut_mode, CutMode::separate);
    EXPECT_EQ(s.tools[0].cut_pressure_pa, 1e3);
    EXPECT_EQ(s.tools[0].wet_rate_per_s, 5.0);
}

TEST(SceneParse, BadToolContactKeysNameTheKeyPath)
{
    const auto with_key = [](const char* key, const json& value) {
        json tool = {{"name", "b"}, {"shape", "blade"}, {"size_mm", {40, 1, 20}}};
        tool[key] = value;
        // The faulty tool is the second, so the index in the path is checked too.
        return scene_error(scene_with_tools(json::array({{{"name", "p"}, {"shape", "sphere"}, {"radius_mm", 5}}, tool})));
    };
    EXPECT_EQ(with_key("push_margin_mm", -0.1), "s.json: tools[1].push_margin_mm: must be in [0, 100], got -0.1");
    EXPECT_EQ(with_key("push_margin_mm", 100.5), "s.json: tools[1].push_margin_mm: must be in [0, 100], got 100.5");
    EXPECT_EQ(with_key("push_margin_mm", "1"), "s.json: tools[1].push_margin_mm: expected a number, got \"1\"");
    EXPECT_EQ(with_key("contact_stiffness_n_per_mm", 0),
              "s.json: tools[1].contact_stiffness_n_per_mm: must be in (0, 10000], got 0");
    EXPECT_EQ(with_key("contact_stiffness_n_per_mm", 2e4),
              "s.json: tools[1].contact_stiffness_n_per_mm: must be in (0, 10000], got 20000.0");
    EXPECT_EQ(with_key("contact_stiffness_n_per_mm", json::array({5})),
              "s.json: tools[1].contact_stiffness_n_per_mm: expected a number, got [5]");
    EXPECT_EQ(with_key("cut_pressure_pa", -1), "s.json: tools[1].cut_pressure_pa: must be in (0, 1e+09], got -1");
    EXPECT_EQ(with_key("cut_pressure_pa", 0.0), "s.json: tools[1].cut_pressure_pa: must be in (0, 1e+09], got 0.0");
    EXPECT_EQ(with_key("cut_pressure_pa", 2e9),
              "s.json: tools[1].cut_pressure_pa: must be in (0, 1e+09], got 2000000000.0");
    EXPECT_EQ(with_key("cut_pressure_pa", true), "s.json: tools[1].cut_pressure_pa: expected a number, got true");
    EXPECT_EQ(with_key("wet_rate_per_s", 0), "s.json: tools[1].wet_rate_per_s: must be in (0, 1000], got 0");
    EXPECT_EQ(with_key("wet_rate_per_s", 1001), "s.json: tools[1].wet_rate_per_s: must be in (0, 1000], got 1001");
    EXPECT_EQ(with_key("wet_rate_per_s", nullptr), "s.json: tools[1].wet_rate_per_s: expected a number, got null");
    EXPECT_EQ(with_key("action", "slice"),
              "s.json: tools[1].action: expected one of \"push\", \"cut\", \"wet\", \"drill\", got \"slice\"");
    EXPECT_EQ(with_key("action", "Cut"),
              "s.json: tools[1].action: expected one of \"push\", \"cut\", \"wet\", \"drill\", got \"Cut\"");
    EXPECT_EQ(with_key("action", 1), "s.json: tools[1].action: expected a string, got 1");
    EXPECT_EQ(with_key("cut_mode", "split"),
              "s.json: tools[1].cut_mode: expected one of \"remove\", \"separate\", got \"split\"");
    EXPECT_EQ(with_key("cut_mode", json::object()), "s.json: tools[1].cut_mode: expected a string, got {}");
    EXPECT_EQ(with_key("two_phase", 1), "s.json: tools[1].two_phase: expected true or false, got 1");
    EXPECT_EQ(with_key("two_phase", "yes"), "s.json: tools[1].two_phase: expected true or false, got \"yes\"");
    // (A blade's default cut_mode is "remove".)
    EXPECT_NE(with_key("two_phase", true).find("tools[1].two_phase: two-phase cutting marks a cut to open whole"), std::string::npos);
    // A misspelt key is still unknown, and the message lists the new keys among the known ones.
    EXPECT_EQ(with_key("cut_pressure", 1e4),
              "s.json: tools[1].cut_pressure: unknown key for a blade tool (known keys: name, shape, size_mm, action, "
              "cut_mode, push_margin_mm, contact_stiffness_n_per_mm, coupling_stiffness_n_per_mm, cut_pressure_pa, wet_rate_per_s, burr_speed_rpm, "
              "drill_rate_mm3_per_n_rev, device_frame, haptic_subdivision, two_phase)");
    EXPECT_EQ(with_key("device_frame", {{"scale", 0}}), "s.json: tools[1].device_frame.scale: must be in (0, 100], got 0");
    EXPECT_EQ(with_key("device_frame", {{"origin", {0, 0, 0}}}).rfind("s.json: tools[1].device_frame.origin: unknown key for a device frame", 0), 0u);
    EXPECT_EQ(with_key("device_frame", {{"rotation_wxyz", {0, 0, 0, 0}}}).rfind("s.json: tools[1].device_frame.rotation_wxyz: the quaternion's norm 0", 0), 0u);
    EXPECT_EQ(with_key("haptic_subdivision", 4).rfind("s.json: tools[1].haptic_subdivision: must be in [-1, 3]", 0), 0u);
    // (A blade cuts by default.)
    EXPECT_EQ(with_key("haptic_subdivision", 1).rfind("s.json: tools[1].haptic_subdivision: haptic subdivision is for tools that push or wet", 0),
              0u);
    // NaN cannot be in a file but can be in a document built in code.
    EXPECT_EQ(with_key("push_margin_mm", std::nan("")).rfind("s.json: tools[1].push_margin_mm: must be in [0, 100]", 0),
              0u);
}

TEST(SceneParse, ScriptOrientationIsReadAndNormalised)
{
    const json tools = json::parse(R"([{"name": "blade", "shape": "blade", "size_mm": [40, 1, 20]}])");
    const json script = json::parse(R"([
        {"t_s": 0, "tool": "blade", "position_mm": [0, 0, 0]},
        {"t_s": 1, "tool": "blade", "position_mm": [1, 2, 3], "orientation_wxyz": [2, 0, 0, 2]},
        {"t_s": 2, "tool": "blade", "position_mm": [1, 2, 3], "orientation_wxyz": [0, 0, -3, 0]},
        {"t_s": 3, "tool": "blade", "position_mm": [1, 2, 3], "orientation_wxyz": [0, 0, 0, -2e-9]}
    ])");
    const Scene s = parse_scene(scene_with_tools(tools, script), "/tmp", "script.json");
    ASSERT_EQ(s.script.size(), 4u);
    // Absent: identity.
    EXPECT_EQ(s.script[0].orientation.coeffs(), Eigen::Quaterniond::Identity().coeffs());
    // [2, 0, 0, 2]: a quarter turn about z, normalised to [1, 0, 0, 1] / sqrt(2).
    const Eigen::Quaterniond& q = s.script[1].orientation;
    EXPECT_NEAR(q.norm(), 1.0, 1e-15);
    EXPECT_NEAR(q.w(), std::sqrt(0.5), 1e-15);
    EXPECT_EQ(q.x(), 0.0);
    EXPECT_EQ(q.y(), 0.0);
    EXPECT_NEAR(q.z(), std::sqrt(0.5), 1e-15);
    EXPECT_TRUE((q * Eigen::Vector3d::UnitX()).isApprox(Eigen::Vector3d::UnitY(), 1e-15));
    EXPECT_EQ(s.script[1].position_mm, Eigen::Vector3d(1, 2, 3)); // position as before
    // A half turn about -y; the w = 0 quaternion is a rotation like any other.
    EXPECT_EQ(s.script[2].orientation.coeffs(), Eigen::Vector4d(0, -1, 0, 0)); // Eigen stores x, y, z, w
    // A tiny quaternion, just above the 1e-9 floor, still gives a direction: a half turn about z.
    EXPECT_EQ(s.script[3].orientation.coeffs(), Eigen::Vector4d(0, 0, -1, 0));
}

TEST(SceneParse, BadScriptOrientationNamesTheKeyPath)
{
    const json tools = json::parse(R"([{"name": "blade", "shape": "blade", "size_mm": [40, 1, 20]}])");
    const auto with_orientation = [&](const json& value) {
        json script = json::parse(R"([
            {"t_s": 0, "tool": "blade", "position_mm": [0, 0, 0]},
            {"t_s": 1, "tool": "blade", "position_mm": [0, 0, 0]}
        ])");
        script[1]["orientation_wxyz"] = value;
        return scene_error(scene_with_tools(tools, script));
    };
    EXPECT_EQ(with_orientation(json::array({1, 0, 0})),
              "s.json: script[1].orientation_wxyz: expected an array of 4 numbers [w, x, y, z], got [1,0,0]");
    EXPECT_EQ(with_orientation(json::array({1, 0, 0, 0, 0})),
              "s.json: script[1].orientation_wxyz: expected an array of 4 numbers [w, x, y, z], got [1,0,0,0,0]");
    EXPECT_EQ(with_orientation("identity"),
              "s.json: script[1].orientation_wxyz: expected an array of 4 numbers [w, x, y, z], got \"identity\"");
    EXPECT_EQ(with_orientation(json::array({1, 0, "0", 0})),
              "s.json: script[1].orientation_wxyz[2]: expected a number, got \"0\"");
    EXPECT_EQ(with_orientation(json::array({0, 0, 0, 0})),
              "s.json: script[1].orientation_wxyz: the quaternion's norm 0 is below 1e-9 (it gives no rotation)");
    EXPECT_EQ(with_orientation(json::array({1e-10, 0, 0, 0})),
              "s.json: script[1].orientation_wxyz: the quaternion's norm 1e-10 is below 1e-9 (it gives no rotation)");
    // A JSON file cannot hold NaN or infinity; a document built in code can, and is refused.
    EXPECT_EQ(with_orientation(json::array({1.0, std::nan(""), 0.0, 0.0})),
              "s.json: script[1].orientation_wxyz[1]: must be a finite number");
    EXPECT_EQ(with_orientation(json::array({1.0, 0.0, 0.0, -std::numeric_limits<double>::infinity()})),
              "s.json: script[1].orientation_wxyz[3]: must be a finite number");
    // Huge but finite components are normalised without overflow.
    json doc = scene_with_tools(tools, json::array({{{"t_s", 0},
                                                     {"tool", "blade"},
                                                     {"position_mm", {0, 0, 0}},
                                                     {"orientation_wxyz", {1e308, 0, 0, 1e308}}}}));
    const Scene s = parse_scene(doc, "/tmp", "s.json");
    EXPECT_NEAR(s.script[0].orientation.w(), std::sqrt(0.5), 1e-15);
    EXPECT_NEAR(s.script[0].orientation.z(), std::sqrt(0.5), 1e-15);
    // An unknown key beside it is still refused, and orientation_wxyz is listed as known.
    json good = scene_with_tools(tools, json::array({{{"t_s", 0}, {"tool", "blade"}, {"position_mm", {0, 0, 0}}}}));
    good["script"][0]["orientation_wxyz"] = {1, 0, 0, 0};
    EXPECT_NO_THROW(static_cast<void>(parse_scene(good, "/tmp", "s.json")));
    json script = json::parse(R"([{"t_s": 0, "tool": "blade", "position_mm": [0, 0, 0], "orientation": [1, 0, 0, 0]}])");
    EXPECT_EQ(scene_error(scene_with_tools(tools, script)),
              "s.json: script[0].orientation: unknown key (known keys: t_s, tool, position_mm, orientation_wxyz)");
}

TEST(SceneParse, PathsResolveAgainstTheSceneFolder)
{
    json doc = json::parse(R"({
        "object": {"mesh": "../elephant.off", "voxel_mm": 0.01, "levels": 0},
        "tools": [{"name": "stylus", "shape": "mesh", "mesh": "./../sphere.off"}],
        "output": {"dir": "results/../run1"}
    })");
    const Scene s = parse_scene(doc, scenes_dir, "paths.json");
    EXPECT_EQ(s.object.file, source_dir / "data" / "elephant.off");
    EXPECT_EQ(s.tools[0].mesh, source_dir / "data" / "sphere.off");
    EXPECT_EQ(s.output.dir, scenes_dir / "run1");
    EXPECT_TRUE(s.object.file.is_absolute());

    // An absolute path stays as it is.
    doc["output"]["dir"] = "/var/tmp/vox-run";
    EXPECT_EQ(parse_scene(doc, scenes_dir, "paths.json").output.dir, fs::path("/var/tmp/vox-run"));

    // The same file names seen from another folder do not exist.
    const std::string message = error_of([&] { static_cast<void>(parse_scene(doc, "/nonexistent/scenes", "p.json")); });
    EXPECT_EQ(message, "p.json: object.mesh: file not found: /nonexistent/elephant.off");
}

TEST(SceneParse, RelativeFolderIsMadeAbsolute)
{
    const Scene s = parse_scene(minimal_scene(), "some/folder", "r.json");
    EXPECT_TRUE(s.folder.is_absolute());
    EXPECT_EQ(s.output.dir, (fs::current_path() / "some/folder/out").lexically_normal());
}

TEST(SceneParse, SolverMaterialAndLevelChoiceKeys)
{
    const fs::path path = write_temp("scene_new_keys.json", R"({
        "object": {"phantom": {"shape": "beam"}, "levels": "auto", "max_error": 0.1},
        "materials": {"default": {"plasticity": {"yield_strain": 0.02}, "wetting": {"stiffness_ratio": 0.3}}},
        "solver": {"preconditioner": "multigrid", "mass": "consistent"},
        "wet_regions": [{"box_mm": [[0, 0, 0], [10, 10, 10]], "water": 0.25}, {"box_mm": [[0, 0, 0], [1, 1, 1]]}]
    })");
    const Scene s = load_scene(path);
    EXPECT_TRUE(s.object.auto_levels);
    EXPECT_EQ(s.object.max_error, 0.1);
    EXPECT_FALSE(s.object.step_budget_ms.has_value());
    ASSERT_TRUE(s.default_material.plasticity.has_value());
    EXPECT_EQ(s.default_material.plasticity->yield_strain, 0.02);
    EXPECT_EQ(s.default_material.plasticity->creep_per_s, 20.0); // documented defaults
    EXPECT_EQ(s.default_material.plasticity->max_strain, 0.5);
    EXPECT_EQ(s.default_material.wetting.stiffness_ratio, 0.3);
    EXPECT_EQ(s.default_material.wetting.yield_ratio, 0.5);
    EXPECT_EQ(s.solver.preconditioner, vox::io::PreconditionerChoice::multigrid);
    EXPECT_FALSE(s.solver.lumped_mass);
    ASSERT_EQ(s.wet_regions.size(), 2u);
    EXPECT_EQ(s.wet_regions[0].water, 0.25);
    EXPECT_EQ(s.wet_regions[1].water, 1.0);

    const Scene plain = parse_scene(minimal_scene(), "/tmp", "plain.json");
    EXPECT_FALSE(plain.default_material.plasticity.has_value()); // elastic unless asked
    EXPECT_TRUE(plain.solver.lumped_mass);
    EXPECT_EQ(plain.solver.preconditioner, vox::io::PreconditionerChoice::automatic);
}

TEST(SceneParse, CommentsAreAllowed)
{
    const fs::path path = write_temp("scene_with_comments.json", R"({
        // a block phantom
        "object": {"phantom": {"shape": "block"}, /* the finest level */ "levels": 0}
    })");
    EXPECT_EQ(load_scene(path).object.phantom.shape, vox::grid::PhantomShape::block);
}

TEST(SceneParse, ErrorsFoundLaterUseTheSameFormat)
{
    const Scene s = parse_scene(minimal_scene(), "/tmp", "scenes/beam.json");
    EXPECT_EQ(std::string(s.error("constraints[0].box_mm", "catches no node").what()),
              "scenes/beam.json: constraints[0].box_mm: catches no node");
}

// ---------------------------------------------------------------------------------------------
// Malformed scenes: each names the file and the exact key path.
// ---------------------------------------------------------------------------------------------

struct BadScene {
    const char* name;     ///< tests/data/bad/scene_NAME.json
    const char* key_path; ///< the message is "FILE: KEY_PATH: ..."; empty for the top level
    const char* problem;  ///< part of the rest of the message
};

void PrintTo(const BadScene& b, std::ostream* os) { *os << b.name; }

const BadScene bad_scenes[] = {
    BadScene{"unknown_key", "toolz",
             "unknown key (known keys: object, materials, solver, gravity_m_s2, constraints, obstacles, piece_contact, loads, wet_regions, tools, script, "
             "output)"},
    BadScene{"unknown_phantom_key", "object.phantom.radius_mm",
             "unknown key for a beam phantom (known keys: shape, voxel_mm, size_mm)"},
    BadScene{"wrong_type", "object.select.label[0]", "expected an integer, got \"abc\""},
    BadScene{"missing_file", "object.volume", "file not found: "},
    BadScene{"negative_dt", "solver.dt_s", "must be in (0, 10], got -0.01"},
    BadScene{"dt_huge", "solver.dt_s", "must be in (0, 10], got 1e+300"},
    BadScene{"gravity_huge", "gravity_m_s2", "is stronger than 1000 m/s^2"},
    BadScene{"empty_tool_name", "tools[0].name", "a tool needs a name"},
    BadScene{"duplicate_tool_name", "tools[1].name", "a tool named \"blade\" is already declared (tools[0])"},
    BadScene{"undeclared_tool", "script[1].tool", "no tool named \"blad\" in tools (declared: \"blade\")"},
    BadScene{"time_order", "script[2].t_s", "0.5 s is before the previous entry's 1 s"},
    BadScene{"poisson_ratio", "materials.default.poisson_ratio", "must be in (-1, 0.5), got 0.5"},
    BadScene{"two_sources", "object", "takes only one of \"volume\", \"phantom\", \"mesh\""},
    BadScene{"no_object", "object", "required key is missing"},
    BadScene{"inverted_box", "constraints[0].box_mm", "min corner is above max corner along y (10 > 0)"},
    BadScene{"levels_range", "object.levels", "must be in [0, 6], got 7"},
    BadScene{"levels_float", "object.levels", "expected an integer, got 2.5"},
    BadScene{"syntax", "line 3 column 29", "syntax error"},
    BadScene{"duplicate_key", "solver.dt_s", "key given twice"},
    BadScene{"threshold_order", "object.select.threshold", "lower bound 3071 is above upper bound 226"},
    BadScene{"solver_type", "solver.type", "expected one of \"dbg\", \"isxfem\", \"shape_matching\", got \"fem\""},
    BadScene{"solver_mode", "solver.mode", "expected one of \"dynamic\", \"static\", got \"quasistatic\""},
    BadScene{"rayleigh_negative", "solver.rayleigh_mass_per_s", "must be >= 0, got -0.5"},
    BadScene{"newton_zero", "solver.newton_max_iterations", "must be >= 1, got 0"},
    BadScene{"load_without_force", "loads[1].force_n", "required key is missing"},
    BadScene{"load_inverted_box", "loads[0].box_mm", "min corner is above max corner along x (200 > 199)"},
    BadScene{"unselected_label", "materials.labels.127", "label 127 is not in object.select.label"},
    BadScene{"slide_axis", "constraints[0].axes[1]", "expected one of \"x\", \"y\", \"z\", got \"w\""},
    BadScene{"slide_all_axes", "constraints[0].axes", "lists every axis; that is a fixed constraint"},
    BadScene{"slide_no_axis", "constraints[0].axes", "lists no axis; such a constraint holds nothing"},
    BadScene{"fixed_with_axes", "constraints[0].axes", "unknown key for a fixed constraint"},
    BadScene{"not_object", "", "expected an object, got [{\"object\":{}}]"},
    BadScene{"cg_tolerance", "solver.cg_tolerance", "must be in (0, 1), got 1"},
    BadScene{"voxel_zero", "object.phantom.voxel_mm", "must be > 0, got 0"},
    BadScene{"phantom_too_thin", "object.phantom.size_mm[1]", "0.5 mm is not a whole number of 1 mm voxels"},
    BadScene{"voxel_misfit", "object.phantom.voxel_mm",
             "the default size_mm[0] gives 200 mm, which is not a whole number of 3 mm voxels"},
    BadScene{"sphere_radius", "object.phantom.radius_mm", "the diameter 4.5 mm is not a whole number of 1 mm voxels"},
    BadScene{"utube_height", "object.phantom.height_mm", "must exceed its leg_mm"},
    BadScene{"phantom_label_material", "materials.labels.1",
             "only a scan selected by label (or taken whole) has labels"},
    BadScene{"phantom_shape", "object.phantom.shape", "expected one of \"beam\", \"block\""},
    BadScene{"tool_unknown_key", "tools[0].radius_mm", "unknown key for a blade tool"},
    BadScene{"blade_without_size", "tools[0].size_mm", "required key is missing"},
    BadScene{"missing_tool_mesh", "tools[0].mesh", "file not found: "},
    BadScene{"script_unknown_key", "script[0].speed_mm_s", "unknown key"},
    BadScene{"negative_time", "script[0].t_s", "must be >= 0, got -1"},
    BadScene{"position_size", "script[0].position_mm", "expected an array of 3 numbers, got [0,0]"},
    BadScene{"empty_label", "object.select.label", "must list at least one label"},
    BadScene{"label_and_threshold", "object.select", "takes only one of \"label\", \"threshold\""},
    BadScene{"label_key", "materials.labels.abc", "expected an integer label as key"},
    BadScene{"label_density", "materials.labels.255.density_kg_m3", "must be > 0, got -1"},
    BadScene{"youngs_zero", "materials.default.youngs_modulus_pa", "must be > 0, got 0"},
    BadScene{"gravity_type", "gravity_m_s2", "expected an array of 3 numbers, got \"down\""},
    BadScene{"mesh_every_zero", "output.mesh_every_n_frames", "must be >= 1, got 0"},
    BadScene{"output_dir_empty", "output.dir", "expected a path, got an empty string"},
    BadScene{"levels_word", "object.levels", "expected an integer 0 to 6, \"auto\" or {\"fine\", \"coarse\", \"fine_radius_mm\"}"},
    BadScene{"auto_without_target", "object.levels", "needs exactly one of step_budget_ms and max_error"},
    BadScene{"budget_without_auto", "object.step_budget_ms", "only meaningful with \"levels\": \"auto\""},
    BadScene{"plastic_yield", "materials.default.plasticity.yield_strain", "must be > 0, got -0.1"},
    BadScene{"wet_ratio_zero", "materials.default.wetting.stiffness_ratio", "must be in (0, 1], got 0"},
    BadScene{"water_above_one", "wet_regions[0].water", "must be in [0, 1], got 1.5"},
    BadScene{"preconditioner", "solver.preconditioner", "expected one of \"auto\", \"jacobi\""},
    BadScene{"number_overflow", "", "a number too large for a double: '1e999'"},
    BadScene{"deep_nesting", "", "values nested deeper than 64 levels (the limit)"},
    BadScene{"long_tool_name", "", "line 1: a string of 5000 bytes, more than the 4096 a string may have"}};

class SceneBadFile : public testing::TestWithParam<BadScene> {};

TEST_P(SceneBadFile, NamesTheFileAndTheKeyPath)
{
    const BadScene& bad = GetParam();
    const std::string file = (bad_dir / ("scene_" + std::string(bad.name) + ".json")).string();
    ASSERT_TRUE(fs::exists(file)) << file;
    const std::string message = error_of([&] { static_cast<void>(load_scene(file)); });
    const std::string prefix = file + ": " + (*bad.key_path ? std::string(bad.key_path) + ": " : "");
    EXPECT_EQ(message.substr(0, prefix.size()), prefix) << message;
    EXPECT_NE(message.find(bad.problem, prefix.size()), std::string::npos) << message;
}

INSTANTIATE_TEST_SUITE_P(Scene, SceneBadFile, testing::ValuesIn(bad_scenes),
                         [](const testing::TestParamInfo<BadScene>& param) { return std::string(param.param.name); });

TEST(SceneMalformed, EveryBadSceneFileIsInTheTable)
{
    // A bad scene added without a table entry would never be checked.
    std::set<std::string> files;
    for (const fs::directory_entry& entry : fs::directory_iterator(bad_dir)) {
        const std::string name = entry.path().filename().string();
        if (name.rfind("scene_", 0) == 0) {
            files.insert(name);
        }
    }
    std::set<std::string> listed;
    for (const BadScene& bad : bad_scenes) {
        listed.insert("scene_" + std::string(bad.name) + ".json");
    }
    EXPECT_EQ(files, listed);
}

TEST(SceneMalformed, WrongTypeMessageIsExact)
{
    const std::string file = (bad_dir / "scene_wrong_type.json").string();
    EXPECT_EQ(error_of([&] { static_cast<void>(load_scene(file)); }),
              file + ": object.select.label[0]: expected an integer, got \"abc\"");
}

TEST(SceneMalformed, MissingFileNamesTheResolvedPath)
{
    const std::string file = (bad_dir / "scene_missing_file.json").string();
    EXPECT_EQ(error_of([&] { static_cast<void>(load_scene(file)); }),
              file + ": object.volume: file not found: " + (bad_dir / "no_such_scan.inr.gz").string());
}

TEST(SceneMalformed, MissingSceneFileIsNamed)
{
    const std::string file = (bad_dir / "scene_that_does_not_exist.json").string();
    const std::string message = error_of([&] { static_cast<void>(load_scene(file)); });
    EXPECT_EQ(message.rfind(file + ": ", 0), 0u) << message;
}

TEST(SceneMalformed, DuplicateKeysInsideArraysNameTheElement)
{
    const fs::path path = write_temp("scene_duplicate_in_array.json", R"({
        "object": {"phantom": {"shape": "beam"}, "levels": 0},
        "constraints": [
            {"type": "fixed", "box_mm": [[0, 0, 0], [1, 1, 1]]},
            {"type": "fixed", "box_mm": [[0, 0, 0], [1, 1, 1]], "type": "slide"}
        ]
    })");
    EXPECT_EQ(error_of([&] { static_cast<void>(load_scene(path)); }),
              path.string() + ": constraints[1].type: key given twice");
}

TEST(SceneMalformed, OddKeysAreQuotedInThePath)
{
    json doc = minimal_scene();
    doc["solver"] = {{"dt s", 0.01}};
    EXPECT_EQ(error_of([&] { static_cast<void>(parse_scene(doc, "/tmp", "odd.json")); }).rfind(
                  "odd.json: solver[\"dt s\"]: unknown key", 0),
              0u);
}

/// Every JSON object in `value` (the top level included), as a JSON pointer and a key path.
void collect_objects(const json& value, const json::json_pointer& pointer, const std::string& path,
                     std::vector<std::pair<json::json_pointer, std::string>>& out)
{
    if (value.is_object()) {
        out.emplace_back(pointer, path);
        for (const auto& [key, member] : value.items()) {
            collect_objects(member, pointer / key, path.empty() ? key : path + "." + key, out);
        }
    } else if (value.is_array()) {
        for (std::size_t i = 0; i < value.size(); ++i) {
            collect_objects(value[i], pointer / i, path + "[" + std::to_string(i) + "]", out);
        }
    }
}

TEST(SceneMalformed, UnknownKeyIsRefusedAtEveryNestingLevel)
{
    // Between them the examples hold every kind of JSON object the format has, except a load
    // (no example has one; SceneParse.BadLoads checks an unknown key in it).
    std::size_t checked = 0;
    for (const char* name : {"liver.json", "beam.json", "elephant.json", "cylinder.json"}) {
        const json original = read_json(scenes_dir / name);
        std::vector<std::pair<json::json_pointer, std::string>> objects;
        collect_objects(original, json::json_pointer(), "", objects);
        for (const auto& [pointer, path] : objects) {
            json doc = original;
            doc[pointer]["bogus_key"] = 1;
            const std::string key_path = path.empty() ? "bogus_key" : path + ".bogus_key";
            SCOPED_TRACE(std::string(name) + " " + key_path);
            const std::string message = error_of([&] { static_cast<void>(parse_scene(doc, scenes_dir, name)); });
            EXPECT_EQ(message.rfind(std::string(name) + ": " + key_path + ": ", 0), 0u) << message;
            ++checked;
        }
    }
    EXPECT_GE(checked, 30u);
}

} // namespace

TEST(SceneParse, ADeviceFrameIsReadWithItsDefaults)
{
    json tools = json::array({{{"name", "probe"}, {"shape", "sphere"}, {"radius_mm", 4},
                               {"device_frame", {{"origin_mm", {10, 20, 30}}, {"rotation_wxyz", {0, 0, 0, 2}}, {"scale", 2.5}}}},
                              {{"name", "other"}, {"shape", "sphere"}, {"radius_mm", 4}, {"device_frame", json::object()}},
                              {{"name", "none"}, {"shape", "sphere"}, {"radius_mm", 4}}});
    const Scene s = parse_scene(scene_with_tools(tools), "/tmp", "s.json");
    ASSERT_TRUE(s.tools[0].device_frame.has_value());
    EXPECT_EQ(s.tools[0].device_frame->origin_mm, Eigen::Vector3d(10, 20, 30));
    EXPECT_TRUE(s.tools[0].device_frame->rotation.isApprox(Eigen::Quaterniond(0, 0, 0, 1), 1e-15)); // normalised
    EXPECT_EQ(s.tools[0].device_frame->scale, 2.5);
    ASSERT_TRUE(s.tools[1].device_frame.has_value());
    EXPECT_EQ(s.tools[1].device_frame->origin_mm, Eigen::Vector3d::Zero());
    EXPECT_EQ(s.tools[1].device_frame->scale, 1.0);
    EXPECT_FALSE(s.tools[2].device_frame.has_value());
}
