// Bad input through the program: every file of the malformed corpus (tests/data/bad) and the usual
// mistakes get one line on stderr naming the thing and the problem, exit code 2, and no output.

#include "app/run_command.hpp"
#include "test_support.hpp"

#include <gtest/gtest.h>

#include <sys/resource.h>

#include <algorithm>
#include <chrono>
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
        // Under a memory limit: the corrupt .vdb files would otherwise grow to gigabytes before
        // their reader is stopped.
        const auto r = name.starts_with("scene_")
                           ? run_voxsculpt("--max-memory-mb 512 check " + quote(file))
                           : run_voxsculpt("--max-memory-mb 512 import " + quote(file) + " -o " + quote((out / "o.vdb").string()));
        expect_clean_refusal(r, file, out);
        ++checked;
    }
    EXPECT_GE(checked, 10);
}

TEST(MalformedInput, FuzzFindingsAnswerInSecondsWithinTheMemoryLimit)
{
    // The commands of ../shared/data/fuzz-findings/README.md on the corpus copies of its inputs:
    // each crashed, hung, grew to gigabytes or left an empty folder behind.
    struct Finding {
        const char* file;
        const char* command; ///< FILE and OUT are replaced
        const char* reason;
    };
    const std::vector<Finding> findings = {
        {"vdb_segfault.vdb", "--max-memory-mb 512 info FILE --json", "not a readable OpenVDB file"},
        {"vdb_hang_memory_a.vdb", "--max-memory-mb 512 info FILE", "memory limit of 512 MiB"},
        {"vdb_hang_memory_b.vdb", "--max-memory-mb 512 import FILE -o OUT/out.vdb", "memory limit of 512 MiB"},
        {"vdb_hang_spin.vdb", "--max-memory-mb 512 import FILE -o OUT/out.vdb", "did not finish within 3 s"},
        {"vdb_heap_corruption.vdb", "--max-memory-mb 512 import FILE -o OUT/out.vdb", "not a readable OpenVDB file"},
        {"nii_gz_vox_offset_past_end.nii.gz", "import FILE -o OUT/out.vdb", "truncated"},
        {"nrrd_gzip_trailer_cut.nrrd", "info FILE", "ends before its checksum"},
        {"nrrd_huge_origin.nrrd", "info FILE", "beyond the 1e6 mm (1 km) limit"},
        {"obj_huge_polygon.obj", "import FILE -o OUT/out.vdb", "more than the 256 a face may have"},
        {"scene_deep_nesting.json", "--max-memory-mb 512 check FILE", "nested deeper than 64 levels"},
        {"scene_dt_huge.json", "run FILE --frames 3 --out OUT/outdir", "solver.dt_s"},
        {"scene_gravity_huge.json", "run FILE --frames 3 --out OUT/outdir", "gravity_m_s2"},
    };
    for (const Finding& f : findings) {
        SCOPED_TRACE(f.file);
        const fs::path out = fresh_dir(std::string("finding_") + f.file);
        const std::string file = VOX_TEST_DATA_DIR "/bad/" + std::string(f.file);
        std::string command = f.command;
        command.replace(command.find("FILE"), 4, quote(file));
        if (const std::size_t at = command.find("OUT"); at != std::string::npos) command.replace(at, 3, quote(out.string()));
        const auto start = std::chrono::steady_clock::now();
        const auto r = run_voxsculpt(command);
        const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
        expect_clean_refusal(r, file + ": ", out);
        EXPECT_NE(r.err.find(f.reason), std::string::npos) << r.err;
        EXPECT_LT(seconds, 10.0);
    }
    // The largest resident size of any process these commands ran (the reader's child included).
    rusage usage{};
    getrusage(RUSAGE_CHILDREN, &usage);
    EXPECT_LT(usage.ru_maxrss, 600L * 1024) << "KiB";
}

TEST(MalformedInput, AHundredMegabyteNameIsNeitherEchoedNorHeld)
{
    // A scene whose tool name is 100 MB: refused before the parser holds the string, in one short line.
    const fs::path d = fresh_dir("bad_long_name");
    const fs::path scene = d / "scene.json";
    {
        std::ofstream s(scene);
        s << R"({"object": {"phantom": {"shape": "beam"}, "levels": 0}, "tools": [{"name": ")";
        const std::string chunk(1 << 20, 'n');
        for (int i = 0; i < 100; ++i) s << chunk;
        s << R"(", "shape": "sphere", "radius_mm": 3}]})";
    }
    const auto r = run_voxsculpt("--max-memory-mb 1024 check " + quote(scene.string()));
    EXPECT_EQ(r.exit_code, 2);
    EXPECT_NE(r.err.find(scene.string() + ": line 1: a string of 104857600 bytes, more than the 4096"), std::string::npos)
        << r.err.substr(0, 300);
    EXPECT_LT(r.err.size(), 300u);
    rusage usage{};
    getrusage(RUSAGE_CHILDREN, &usage);
    EXPECT_LT(usage.ru_maxrss, 300L * 1024) << "KiB: the file's 100 MB once, not copies of it";
    fs::remove(scene);
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
                         "the selection (label 7) holds no voxel; stored values present (5 distinct, in 25511310 voxels; smallest first, "
                         "with their voxels): 0 (22019024), 84 (2), 85 (17702), 127 (314086), 255 (3160496)",
                         out);
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

TEST(MalformedInput, AnAbsurdLoadIsRefusedBeforeTheRunAndLeavesNothingBehind)
{
    // 1e9 N on a soft beam: before steps that create energy lost it again (energy projection), the
    // run stopped in its first frames; now nothing stops a run, and such a load is refused with
    // the scene. Neither the output folder nor a staging folder may appear.
    const fs::path d = fresh_dir("bad_run_midway");
    std::ofstream(d / "scene.json") << R"({"object": {"phantom": {"shape": "beam"}, "levels": 2, "unheld_pieces": "fall"},
        "loads": [{"box_mm": [[190, -1, -1], [201, 11, 11]], "force_n": [0, 0, -1e9]}],
        "output": {"mesh_every_n_frames": 1}})";
    const auto r = run_voxsculpt("run " + quote((d / "scene.json").string()) + " --frames 5 --out " + quote((d / "out").string()));
    EXPECT_EQ(r.exit_code, 2) << r.err;
    EXPECT_NE(r.err.find("loads[0].force_n: is stronger than 1e6 N"), std::string::npos) << r.err;
    EXPECT_FALSE(fs::exists(d / "out"));
    for (const auto& entry : fs::directory_iterator(d)) EXPECT_EQ(entry.path().filename(), "scene.json") << "left behind: " << entry.path();
}
