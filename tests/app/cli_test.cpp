// The voxsculpt program end to end: import -> .vdb -> info, phantoms, usage errors.

#include "app/run_command.hpp"
#include "test_support.hpp"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <regex>
#include <vector>

namespace fs = std::filesystem;
using vox::test::fresh_dir;
using vox::test::info_json;
using vox::test::quote;
using vox::test::run_voxsculpt;

TEST(Cli, LiverImportRoundTripKeepsCountsAndTransform)
{
    const fs::path d = fresh_dir("cli_liver");
    const std::string liver = VOX_SOURCE_DIR "/data/liver.inr.gz";
    const auto r = run_voxsculpt("import " + quote(liver) + " --label 255 -o " + quote((d / "liver.vdb").string()));
    ASSERT_EQ(r.exit_code, 0) << r.err;
    const auto scan = info_json(liver);
    const auto vdb = info_json(d / "liver.vdb");
    EXPECT_EQ(vdb["active_voxels"], 3160496);
    EXPECT_EQ(vdb["labels"]["255"], 3160496);
    EXPECT_EQ(scan["labels"]["255"], 3160496);
    EXPECT_EQ(scan["active_voxels"], 3160496 + 314086 + 17702 + 2);
    for (int r0 = 0; r0 < 4; ++r0)
        for (int c = 0; c < 4; ++c)
            EXPECT_NEAR(vdb["index_to_world"][r0][c].get<double>(), scan["index_to_world"][r0][c].get<double>(), 1e-12);
    // The liver's voxels lie inside the scan's box.
    for (int a = 0; a < 3; ++a) {
        EXPECT_GE(vdb["world_bbox_mm"]["min"][a].get<double>(), scan["world_bbox_mm"]["min"][a].get<double>());
        EXPECT_LE(vdb["world_bbox_mm"]["max"][a].get<double>(), scan["world_bbox_mm"]["max"][a].get<double>());
    }
    // Re-importing the .vdb with a selection keeps the voxels and transform again.
    const auto r2 = run_voxsculpt("import " + quote((d / "liver.vdb").string()) + " --label 255 -o " +
                                  quote((d / "again.vdb").string()));
    ASSERT_EQ(r2.exit_code, 0) << r2.err;
    EXPECT_EQ(info_json(d / "again.vdb")["active_voxels"], 3160496);
}

TEST(Cli, ThresholdSelectionGivesLabelOne)
{
    const fs::path d = fresh_dir("cli_threshold");
    const auto r = run_voxsculpt("import " + quote(VOX_SOURCE_DIR "/data/liver.inr.gz") + " --threshold 100:200 -o " +
                                 quote((d / "t.vdb").string()));
    ASSERT_EQ(r.exit_code, 0) << r.err;
    const auto j = info_json(d / "t.vdb");
    EXPECT_EQ(j["labels"]["1"], 314086); // only label 127 lies in [100, 200]
    EXPECT_EQ(j["labels"].size(), 1u);
}

TEST(Cli, PhantomWritesDocumentedSizes)
{
    const fs::path d = fresh_dir("cli_phantom");
    const auto r = run_voxsculpt("phantom beam --size-mm 20 4 6 --voxel-mm 2 -o " + quote((d / "b.vdb").string()));
    ASSERT_EQ(r.exit_code, 0) << r.err;
    const auto j = info_json(d / "b.vdb");
    EXPECT_EQ(j["active_voxels"], 10 * 2 * 3);
    EXPECT_EQ(j["dimensions"], nlohmann::json({10, 2, 3}));
    EXPECT_EQ(j["world_bbox_mm"]["min"], nlohmann::json({-1.0, -1.0, -1.0}));
    EXPECT_EQ(j["world_bbox_mm"]["max"], nlohmann::json({19.0, 3.0, 5.0}));
}

TEST(Cli, HelpAndUsageErrors)
{
    for (const char* sub : {"", "import ", "info ", "phantom ", "phantom sphere ", "check ", "grid ", "export ", "run "}) {
        const auto r = run_voxsculpt(std::string(sub) + "--help");
        EXPECT_EQ(r.exit_code, 0) << sub;
        EXPECT_NE(r.out.find("Usage"), std::string::npos) << sub;
    }
    const auto none = run_voxsculpt("");
    EXPECT_EQ(none.exit_code, 2);
    const auto unknown = run_voxsculpt("frobnicate");
    EXPECT_EQ(unknown.exit_code, 2);
    const auto missing_out = run_voxsculpt("import x.nii");
    EXPECT_EQ(missing_out.exit_code, 2);
    EXPECT_NE(missing_out.err.find("--output"), std::string::npos) << missing_out.err;
}

TEST(Cli, ExportWritesTheClosedSurfaceInWorldMillimetres)
{
    const fs::path d = fresh_dir("cli_export");
    const std::string vdb = (d / "b.vdb").string();
    ASSERT_EQ(run_voxsculpt("phantom block --size-mm 6 4 2 --voxel-mm 2 -o " + quote(vdb)).exit_code, 0);
    for (const char* ext : {"obj", "ply", "stl", "off"}) {
        const std::string mesh = (d / (std::string("b.") + ext)).string();
        const auto r = run_voxsculpt("export " + quote(vdb) + " -o " + quote(mesh));
        ASSERT_EQ(r.exit_code, 0) << r.err;
        const auto j = info_json(mesh);
        // A 3 x 2 x 1 voxel box: 8 + 2 * 4 * (2 + 1 + 0) + 2 * 2 * (2 * 1) = 40 triangles.
        EXPECT_EQ(j["faces"], 40) << ext;
        EXPECT_EQ(j["closed"], true) << ext;
        EXPECT_EQ(j["consistently_oriented"], true) << ext;
        EXPECT_GT(j["enclosed_volume_mm3"].get<double>(), 0.0) << ext;
        // Vertices sit on voxel faces: the box spans [-1, 5] x [-1, 3] x [-1, 1] mm.
        EXPECT_NEAR(j["world_bbox_mm"]["min"][0].get<double>(), -1.0, 1e-6);
        EXPECT_NEAR(j["world_bbox_mm"]["max"][0].get<double>(), 5.0, 1e-6);
    }
    const auto bad = run_voxsculpt("export " + quote(vdb) + " -o " + quote((d / "b.xyz").string()));
    EXPECT_EQ(bad.exit_code, 2);
    EXPECT_NE(bad.err.find("b.xyz"), std::string::npos);
}

TEST(Cli, RunWritesStatsAndDeformedSurfaces)
{
    const fs::path d = fresh_dir("cli_run");
    {
        std::ofstream scene(d / "block.json");
        scene << R"({"object": {"phantom": {"shape": "block", "size_mm": [8, 4, 4]}, "levels": 1},
                    "constraints": [{"type": "fixed", "box_mm": [[-1, -1, -1], [0, 4, 4]]}],
                    "output": {"dir": "results", "mesh_every_n_frames": 2}})";
    }
    const auto r = run_voxsculpt("run " + quote((d / "block.json").string()) + " --frames 5");
    ASSERT_EQ(r.exit_code, 0) << r.err;
    const fs::path out = d / "results"; // relative to the scene's folder
    std::ifstream in(out / "stats.json");
    const nlohmann::json stats = nlohmann::json::parse(in);
    ASSERT_EQ(stats["frames"].size(), 5u);
    for (const char* key : {"step_ms", "cg_iterations", "residual", "kinetic_energy_j", "elastic_energy_j",
                            "max_displacement_mm"})
        EXPECT_TRUE(stats["frames"][0].contains(key)) << key;
    EXPECT_EQ(stats["summary"]["frames"], 5);
    // The block hangs from its left end and sags under gravity.
    EXPECT_GT(stats["summary"]["final_max_displacement_mm"].get<double>(), 0.0);
    EXPECT_TRUE(fs::exists(out / "frame_00002.obj"));
    EXPECT_TRUE(fs::exists(out / "frame_00004.obj"));
    EXPECT_FALSE(fs::exists(out / "frame_00005.obj"));
    const auto j = info_json(out / "final.obj");
    EXPECT_EQ(j["closed"], true);
}

namespace {
/// Writes `scene` into `dir`/NAME.json, runs it and returns its stats.json.
nlohmann::json run_scene(const fs::path& dir, const std::string& name, const std::string& scene, const std::string& options)
{
    std::ofstream(dir / (name + ".json")) << scene;
    const auto r = run_voxsculpt("run " + quote((dir / (name + ".json")).string()) + " --out " + quote((dir / name).string()) + " " + options);
    EXPECT_EQ(r.exit_code, 0) << r.err;
    std::ifstream in(dir / name / "stats.json");
    return nlohmann::json::parse(in);
}
} // namespace

TEST(Cli, APreconditionerThatFailsIsNamedInItsFrameOnceAndCounted)
{
    // Quasi-static with nothing held: K is singular, the warped Cholesky factor fails and Jacobi
    // takes over. The frame it failed in says why, the log warns once, the summary counts it.
    const fs::path d = fresh_dir("cli_preconditioner_fallback");
    std::ofstream(d / "s.json") << R"({"object": {"phantom": {"shape": "beam", "size_mm": [40, 10, 10]}, "levels": 1, "unheld_pieces": "fall"},
        "solver": {"mode": "static", "preconditioner": "cholesky"}})";
    const auto r = run_voxsculpt("run " + quote((d / "s.json").string()) + " --frames 3 --out " + quote((d / "out").string()));
    ASSERT_EQ(r.exit_code, 0) << r.err;
    const auto begin = r.err.find("warped Cholesky preconditioner failed: the step's matrix is ");
    ASSERT_NE(begin, std::string::npos) << r.err;
    const std::string why = r.err.substr(begin, r.err.find("using Jacobi", begin) + 12 - begin);
    EXPECT_NE(why.find("singular"), std::string::npos) << why; // not "not positive definite"
    EXPECT_EQ(why.find("not positive definite"), std::string::npos) << why;
    EXPECT_NE(why.find(" mm (nothing holds the object); using Jacobi"), std::string::npos) << why;
    const auto first = r.err.find(why);
    EXPECT_NE(first, std::string::npos) << r.err;
    EXPECT_EQ(r.err.find(why, first + 1), std::string::npos) << "warned once: " << r.err;
    std::ifstream in(d / "out" / "stats.json");
    const nlohmann::json stats = nlohmann::json::parse(in);
    EXPECT_EQ(stats["frames"][0]["preconditioner_fallback"], why);
    EXPECT_FALSE(stats["frames"][1].contains("preconditioner_fallback"));
    EXPECT_EQ(stats["summary"]["preconditioner_fallbacks"], 1);
    EXPECT_EQ(stats["linear_solver"], why);
}

TEST(Cli, RunAtLevelZeroAndWithAutomaticLevels)
{
    const fs::path d = fresh_dir("cli_run_levels");
    const std::string object = R"("phantom": {"shape": "block", "size_mm": [8, 4, 4]})";
    const std::string rest = R"(, "constraints": [{"type": "fixed", "box_mm": [[-1, -1, -1], [0, 9, 9]]}]})";
    const nlohmann::json zero = run_scene(d, "zero", "{\"object\": {" + object + R"(, "levels": 0})" + rest, "--frames 3");
    EXPECT_EQ(zero["level"], 0);
    EXPECT_EQ(zero["elements"], 128); // every voxel an element
    EXPECT_EQ(info_json(d / "zero" / "final.obj")["closed"], true);

    // A budget every level meets: the finest level, 0, wins.
    const nlohmann::json fast =
        run_scene(d, "budget", "{\"object\": {" + object + R"(, "levels": "auto", "step_budget_ms": 10000})" + rest, "--frames 1");
    EXPECT_EQ(fast["level"], 0);
    EXPECT_NE(fast["level_choice"]["reason"].get<std::string>().find("finest"), std::string::npos);
    EXPECT_GE(fast["level_choice"]["trials"].size(), 2u);

    // An error target any level meets: the coarsest level compared wins.
    const nlohmann::json loose =
        run_scene(d, "error", "{\"object\": {" + object + R"(, "levels": "auto", "max_error": 0.99})" + rest, "--frames 1");
    EXPECT_GE(loose["level"].get<int>(), 1);
    EXPECT_NE(loose["level_choice"]["reason"].get<std::string>().find("coarsest"), std::string::npos);
}

TEST(Cli, AWetObjectSagsByItsSofteningLaw)
{
    // Quasi-static cantilever under gravity, dry against soaked (stiffness ratio 0.2): small
    // deflections scale with 1 / E, so the soaked one sags five times as far.
    const fs::path d = fresh_dir("cli_run_wet");
    const std::string scene = R"({"object": {"phantom": {"shape": "block", "size_mm": [16, 4, 4]}, "levels": 1},
        "materials": {"default": {"youngs_modulus_pa": 1e7, "wetting": {"stiffness_ratio": 0.2}}},
        "solver": {"mode": "static", "cg_tolerance": 1e-9},
        "constraints": [{"type": "fixed", "box_mm": [[-1, -1, -1], [0, 9, 9]]}])";
    const nlohmann::json dry = run_scene(d, "dry", scene + "}", "--frames 1");
    const nlohmann::json wet =
        run_scene(d, "wet", scene + R"(, "wet_regions": [{"box_mm": [[-1, -1, -1], [16, 4, 4]]}]})", "--frames 1");
    const double ratio = wet["summary"]["final_max_displacement_mm"].get<double>() /
                         dry["summary"]["final_max_displacement_mm"].get<double>();
    EXPECT_NEAR(ratio, 5.0, 0.05);
}

TEST(Cli, StabilityQuickSubsetNeverDiverges)
{
    // The test suite's share of `voxsculpt bench stability`: every case stable or refused with a
    // message; the material, time-step, twist and inversion sweeps all stable.
    const fs::path d = fresh_dir("cli_stability");
    const auto r = run_voxsculpt("bench stability --quick --out " + quote(d.string()));
    ASSERT_EQ(r.exit_code, 0) << r.err;
    std::ifstream in(d / "stability.json");
    const nlohmann::json cases = nlohmann::json::parse(in);
    ASSERT_GE(cases.size(), 20u);
    for (const nlohmann::json& c : cases) {
        const std::string outcome = c["outcome"], name = c["case"];
        EXPECT_TRUE(outcome == "stable" || outcome == "refused") << name << ": " << outcome;
        if (outcome == "refused") {
            EXPECT_NE(name.find("100 N"), std::string::npos) << name;
            EXPECT_FALSE(c["detail"].get<std::string>().empty());
        }
    }
    EXPECT_TRUE(fs::exists(d / "stability.md"));
}

TEST(Cli, CcdCheckPrintsTheScoreLine)
{
    const auto r = run_voxsculpt("ccd-check " + quote(VOX_SOURCE_DIR "/data/ccd-queries/unit-tests/vertex-face/data_0_0.csv") + " --type vf");
    ASSERT_EQ(r.exit_code, 0) << r.err;
    EXPECT_EQ(r.out, "true_positives: 35 false_positives: 0 false_negatives: 0 true_negatives: 90\n");
    const auto bad = run_voxsculpt("ccd-check " + quote(VOX_SOURCE_DIR "/data/ccd-queries/README.md") + " --type ee");
    EXPECT_EQ(bad.exit_code, 2);
    EXPECT_NE(bad.err.find("README.md: line 1"), std::string::npos) << bad.err;
}

TEST(Cli, DevicesListsOrExplains)
{
    // Never a silent empty list: for each kind, either device lines or the reason there are none.
    ::unsetenv("VOX_LIBHD");
    ::unsetenv("VOX_LIBDHD");
    const auto r = run_voxsculpt("devices");
    ASSERT_EQ(r.exit_code, 0) << r.err;
    ASSERT_EQ(r.out.rfind("HID controllers", 0), 0u) << r.out;
    const bool listed = std::regex_search(r.out, std::regex("\n  [0-9a-f]{4}:[0-9a-f]{4} "));
    EXPECT_TRUE(listed || r.out.find("no HID devices") != std::string::npos || r.out.find("udev rule") != std::string::npos)
        << r.out;
    // Neither vendor's runtime is installed here.
    EXPECT_NE(r.out.find("  none: libHD.so not found (searched by the dynamic loader"), std::string::npos) << r.out;
    EXPECT_NE(r.out.find("  none: libdhd.so not found (searched by the dynamic loader"), std::string::npos) << r.out;

    // With the fake runtimes on the loader's path: the devices they report.
    ::setenv("LD_LIBRARY_PATH", VOX_FAKE_VENDOR_DIR, 1);
    const auto found = run_voxsculpt("devices");
    ::unsetenv("LD_LIBRARY_PATH");
    ASSERT_EQ(found.exit_code, 0) << found.err;
    EXPECT_NE(found.out.find("  Touch (fake), serial 41295300123, maximum force 3.30 N"), std::string::npos) << found.out;
    EXPECT_NE(found.out.find("  omega.6 (fake), serial 1207, maximum force 12.00 N"), std::string::npos) << found.out;
}

TEST(Cli, QuietPrintsNothingOnSuccess)
{
    const fs::path d = fresh_dir("cli_quiet");
    const auto r = run_voxsculpt("phantom block -o " + quote((d / "b.vdb").string()) + " --quiet");
    EXPECT_EQ(r.exit_code, 0);
    EXPECT_EQ(r.err, "");
    EXPECT_EQ(r.out, "");
}

TEST(Cli, ADicomFolderIsListedReadInASceneAndNoPatientIdentifierIsWritten)
{
    // pydicom writes 60 slices of the liver for patient "Test^Liver", ID VOX-TEST-0001
    // (tests/io/write_dicom_series.py); neither may reach what the program prints or writes.
    const fs::path d = fresh_dir("cli_dicom");
    const std::string dir = (d / "export").string();
    ASSERT_EQ(vox::test::run_python(VOX_SOURCE_DIR "/tests/io/write_dicom_series.py",
                                    {VOX_SOURCE_DIR "/data/liver.inr.gz", dir, "--slices", "60", "--shuffle"}),
              0);
    const auto no_identifier = [](const std::string& text, const std::string& what) {
        EXPECT_EQ(text.find("Test^Liver"), std::string::npos) << what;
        EXPECT_EQ(text.find("VOX-TEST"), std::string::npos) << what;
    };

    const auto info = run_voxsculpt("info " + quote(dir));
    ASSERT_EQ(info.exit_code, 0) << info.err;
    EXPECT_NE(info.out.find("1: CT 438x353x60 \"liver labels\""), std::string::npos) << info.out;
    no_identifier(info.out + info.err, "info");
    const auto j = info_json(dir);
    EXPECT_EQ(j["series"].size(), 1u);
    EXPECT_EQ(j["volume"]["dimensions"][2], 60);

    const auto import = run_voxsculpt("import " + quote(dir) + " --series 1 --label 255 -o " + quote((d / "l.vdb").string()));
    ASSERT_EQ(import.exit_code, 0) << import.err;
    no_identifier(import.out + import.err, "import");
    std::ifstream vdb(d / "l.vdb", std::ios::binary);
    no_identifier(std::string(std::istreambuf_iterator<char>(vdb), std::istreambuf_iterator<char>()), "the .vdb");

    std::ofstream(d / "scene.json") << R"({"object": {"volume": "export", "series": 1, "select": {"label": [255]}, "levels": 4},
        "constraints": [{"type": "fixed", "box_mm": [[0, 100, 0], [270, 220, 220]]}]})";
    const auto check = run_voxsculpt("check " + quote((d / "scene.json").string()));
    EXPECT_EQ(check.exit_code, 0) << check.err;
    no_identifier(check.out + check.err, "check");
    std::ofstream(d / "wrong.json") << R"({"object": {"volume": "export", "series": 2}})";
    const auto wrong = run_voxsculpt("check " + quote((d / "wrong.json").string()));
    EXPECT_EQ(wrong.exit_code, 2);
    EXPECT_NE(wrong.err.find("has no series 2"), std::string::npos) << wrong.err;
}

TEST(Cli, InfoOnAScanOfValuesShowsTheirSpreadNotLabels)
{
    // 40^3 int16 voxels cycling through -1000..1000 (2001 values, as a CT's are): info lists no
    // labels but the range and percentiles, which a sort of the same values gives.
    const fs::path d = fresh_dir("cli_info_values");
    std::vector<std::int16_t> values(40 * 40 * 40);
    for (std::size_t n = 0; n < values.size(); ++n) values[n] = static_cast<std::int16_t>(static_cast<int>(n % 2001) - 1000);
    std::ofstream(d / "ct.mhd") << "ObjectType = Image\nNDims = 3\nDimSize = 40 40 40\nElementSpacing = 1 1 1\n"
                                   "ElementType = MET_SHORT\nElementDataFile = ct.raw\n";
    std::ofstream(d / "ct.raw", std::ios::binary)
        .write(reinterpret_cast<const char*>(values.data()), static_cast<std::streamsize>(2 * values.size()));
    const auto j = info_json(d / "ct.mhd");
    EXPECT_FALSE(j.contains("labels"));
    std::vector<double> sorted(values.begin(), values.end());
    std::sort(sorted.begin(), sorted.end());
    EXPECT_EQ(j["values"]["range"], nlohmann::json({-1000.0, 1000.0}));
    for (const int p : {1, 5, 25, 50, 75, 95, 99})
        EXPECT_EQ(j["values"]["percentiles"][std::to_string(p)], sorted[static_cast<std::size_t>(std::llround(0.01 * p * (sorted.size() - 1)))]) << p;
    EXPECT_EQ(j["values"]["sampled_voxels"], 64000);
    const auto text = run_voxsculpt("info " + quote((d / "ct.mhd").string()));
    EXPECT_NE(text.out.find("values (scaled; not labels): range [-1000, 1000], percentiles 1 / 5 / 25 / 50 / 75 / 95 / 99: "), std::string::npos)
        << text.out;
}

TEST(Cli, InfoListsASeriesThatCannotBeImportedWithWhyAndExitsZero)
{
    // A folder with a good series and one missing a slice: info describes both (the second with
    // the reason on its line) and succeeds; import refuses the second with the same reason.
    const fs::path d = fresh_dir("cli_dicom_missing");
    const std::string dir = (d / "export").string();
    ASSERT_EQ(vox::test::run_python(VOX_SOURCE_DIR "/tests/io/write_dicom_series.py",
                                    {VOX_SOURCE_DIR "/data/liver.inr.gz", dir + "/a", "--slices", "10", "--series-number", "1"}),
              0);
    ASSERT_EQ(vox::test::run_python(VOX_SOURCE_DIR "/tests/io/write_dicom_series.py",
                                    {VOX_SOURCE_DIR "/data/liver.inr.gz", dir + "/b", "--slices", "20", "--drop-slice", "8",
                                     "--series-number", "2"}),
              0);
    const auto info = run_voxsculpt("info " + quote(dir));
    ASSERT_EQ(info.exit_code, 0) << info.err;
    EXPECT_NE(info.out.find("  1: CT 438x353x10"), std::string::npos) << info.out;
    EXPECT_NE(info.out.find("  2: CT 438x353x19"), std::string::npos) << info.out;
    EXPECT_NE(info.out.find("     cannot import: series 2 has uneven slice spacing: 2.66666 mm between"), std::string::npos) << info.out;
    const auto picked_run = run_voxsculpt("info --json --series 2 " + quote(dir));
    ASSERT_EQ(picked_run.exit_code, 0) << picked_run.err;
    const auto picked = nlohmann::json::parse(picked_run.out);
    EXPECT_FALSE(picked.contains("volume"));
    EXPECT_FALSE(picked["series"][0].contains("cannot_import"));
    EXPECT_EQ(picked["series"][1]["cannot_import"].get<std::string>().rfind("series 2 has uneven slice spacing", 0), 0u);
    const auto import = run_voxsculpt("import " + quote(dir) + " --series 2 -o " + quote((d / "b.vdb").string()));
    EXPECT_EQ(import.exit_code, 2);
    EXPECT_NE(import.err.find("series 2 has uneven slice spacing"), std::string::npos) << import.err;
    EXPECT_FALSE(fs::exists(d / "b.vdb"));
}

TEST(Cli, ARunThatRunsAwayStopsWithExit2NamingWhereAndWritesNothing)
{
    // Is-XFEM steps solved with two CG iterations (what a far too loose solver does) while a probe
    // presses into a held block: the state runs away geometrically. The run stops with one line
    // naming the frame, the element's place and its stretch, exit 2, and no output folder; it
    // used to go on to 1e39 mm and end with exit 0.
    const fs::path d = fresh_dir("cli_runaway");
    std::ofstream(d / "runaway.json") << R"({"object": {"phantom": {"shape": "block", "size_mm": [12, 12, 8]}, "levels": 1},
        "materials": {"default": {"youngs_modulus_pa": 3e4, "poisson_ratio": 0.45, "density_kg_m3": 1000}},
        "solver": {"type": "isxfem", "dt_s": 0.01, "cg_max_iterations": 2, "preconditioner": "jacobi"}, "gravity_m_s2": [0, 0, 0],
        "constraints": [{"type": "fixed", "box_mm": [[-1, -1, -1], [13, 13, 0.2]]}],
        "tools": [{"name": "probe", "shape": "sphere", "radius_mm": 3.0, "action": "push", "push_margin_mm": 0.25}],
        "script": [{"t_s": 0, "tool": "probe", "position_mm": [5.5, 5.5, 10.5]}, {"t_s": 0.5, "tool": "probe", "position_mm": [5.5, 5.5, 3.5]}]})";
    const auto r = run_voxsculpt("run " + quote((d / "runaway.json").string()) + " --frames 100 --out " + quote((d / "out").string()));
    EXPECT_EQ(r.exit_code, 2);
    EXPECT_NE(r.err.find("runaway.json: the simulation diverged at frame "), std::string::npos) << r.err;
    EXPECT_NE(r.err.find(" times its size, more each frame (the step did not converge: residual "), std::string::npos) << r.err;
    EXPECT_FALSE(fs::exists(d / "out"));
}
