// Bad input through the program: every file of the malformed corpus (tests/data/bad) and the usual
// mistakes get one line on stderr naming the thing and the problem, exit code 2, and no output.

#include "app/run_command.hpp"
#include "test_support.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <filesystem>

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
