// Bad input through the program: every file of the malformed corpus (tests/data/bad) and the usual
// mistakes get one line on stderr naming the thing and the problem, exit code 2, and no output.

#include "app/run_command.hpp"
#include "test_support.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <filesystem>
#include <fstream>

namespace fs = std::filesystem;
using vox::test::fresh_dir;
using vox::test::quote;
using vox::test::run_voxsculpt;

namespace {

/// Exit 2, exactly one line on stderr that contains `must_mention`, and `out_dir` left empty.
void expect_clean_refusal(const vox::test::CommandResult& r, const std::string& must_mention, const fs::path& out_dir)
{
    EXPECT_EQ(r.exit_code, 2) << r.err;
    EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << r.err;
    EXPECT_NE(r.err.find(must_mention), std::string::npos) << r.err;
    EXPECT_TRUE(fs::is_empty(out_dir)) << "output left behind for " << must_mention;
}

} // namespace

TEST(MalformedInput, EveryCorpusFileIsRefusedCleanly)
{
    int checked = 0;
    for (const auto& entry : fs::directory_iterator(VOX_TEST_DATA_DIR "/bad")) {
        const std::string name = entry.path().filename().string();
        if (name == "README.md" || name.ends_with(".raw")) continue; // documentation, detached data
        SCOPED_TRACE(name);
        const fs::path out = fresh_dir("bad_" + name);
        const std::string file = entry.path().string();
        const auto r = name.starts_with("scene_")
                           ? run_voxsculpt("check " + quote(file))
                           : run_voxsculpt("import " + quote(file) + " -o " + quote((out / "o.vdb").string()));
        expect_clean_refusal(r, file, out);
        ++checked;
    }
    EXPECT_GE(checked, 10);
}

TEST(MalformedInput, UsualMistakes)
{
    const fs::path out = fresh_dir("bad_mistakes");
    const std::string o = quote((out / "o.vdb").string());
    const std::string liver = VOX_SOURCE_DIR "/data/liver.inr.gz";

    expect_clean_refusal(run_voxsculpt("import /nonexistent/scan.nii -o " + o), "/nonexistent/scan.nii: no such file",
                         out);
    expect_clean_refusal(run_voxsculpt("import " + quote(out.string() + "/") + "x.nrrd -o " + o), "x.nrrd", out);
    expect_clean_refusal(run_voxsculpt("import " + quote(liver) + " --label 7 -o " + o),
                         "the selection (label 7) holds no voxel; stored values present: 0, 84, 85, 127, 255", out);
    expect_clean_refusal(run_voxsculpt("import " + quote(liver) + " --max-memory-mb 10 -o " + o),
                         "more than the memory limit of 10 MiB", out);
    expect_clean_refusal(run_voxsculpt("import " + quote(liver) + " --label 255 --threshold 1 -o " + o),
                         "cannot be combined", out);
    expect_clean_refusal(run_voxsculpt("import " + quote(liver) + " --threshold 5:1 -o " + o), "LO is greater than HI",
                         out);
    expect_clean_refusal(run_voxsculpt("import " + quote(liver) + " -o " + quote((out / "o.nii").string())),
                         "must be an OpenVDB file", out);
    expect_clean_refusal(run_voxsculpt("import " + quote(VOX_SOURCE_DIR "/data/sphere.off") + " --voxel-size -1 -o " + o),
                         "--voxel-size", out);
    expect_clean_refusal(run_voxsculpt("import " + quote(VOX_SOURCE_DIR "/data/sphere.off") + " --label 3 -o " + o),
                         "a mesh is voxelised whole", out);
    expect_clean_refusal(run_voxsculpt("import " + quote(VOX_SOURCE_DIR "/data/cylinder.off") + " -o " + o),
                         "cylinder.off", out);
    expect_clean_refusal(run_voxsculpt("phantom block --voxel-mm 3 -o " + o), "not a whole number", out);
}

TEST(MalformedInput, ARunThatFailsMidwayLeavesNothingBehind)
{
    // Loads far beyond what the beam can follow: the run stops at its first frame. Its output
    // folder must not appear (it is written in a staging folder moved into place at the end), and
    // no staging folder may be left either.
    const fs::path d = fresh_dir("bad_run_midway");
    std::ofstream(d / "scene.json") << R"({"object": {"phantom": {"shape": "beam"}, "levels": 2},
        "loads": [{"box_mm": [[190, -1, -1], [201, 11, 11]], "force_n": [0, 0, -1e9]}],
        "output": {"mesh_every_n_frames": 1}})";
    const auto r = run_voxsculpt("run " + quote((d / "scene.json").string()) + " --frames 5 --out " + quote((d / "out").string()));
    EXPECT_EQ(r.exit_code, 2) << r.err;
    EXPECT_NE(r.err.find("frame 1"), std::string::npos) << r.err;
    EXPECT_FALSE(fs::exists(d / "out"));
    for (const auto& entry : fs::directory_iterator(d)) EXPECT_EQ(entry.path().filename(), "scene.json") << "left behind: " << entry.path();
}
