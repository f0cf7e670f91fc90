// A run's staging folder: dropped whole when the run fails (no destination, no partial files),
// moved into place when it completes, replacing files of the same names and keeping others.

#include "core/staging_dir.hpp"

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <stdexcept>

namespace fs = std::filesystem;

namespace vox {
namespace {

fs::path fresh(const std::string& name)
{
    const fs::path d = fs::path(::testing::TempDir()) / name;
    fs::remove_all(d);
    fs::create_directories(d);
    return d;
}

TEST(StagingDir, AFailedRunLeavesNothingBehind)
{
    const fs::path d = fresh("staging_failed");
    try {
        StagingDir staging(d / "out");
        std::ofstream(staging.path() / "frame_0001.obj") << "v 0 0 0\n";
        throw std::runtime_error("the run failed midway");
    } catch (const std::runtime_error&) {
    }
    EXPECT_FALSE(fs::exists(d / "out"));
    EXPECT_TRUE(fs::is_empty(d)) << "a staging folder was left behind";
}

TEST(StagingDir, ACompletedRunReplacesFilesOfTheSameNamesAndKeepsOthers)
{
    const fs::path d = fresh("staging_done");
    fs::create_directories(d / "out");
    std::ofstream(d / "out" / "stats.json") << "old";
    std::ofstream(d / "out" / "notes.txt") << "mine";
    {
        StagingDir staging(d / "out");
        std::ofstream(staging.path() / "stats.json") << "new";
        staging.commit();
    }
    std::ifstream stats(d / "out" / "stats.json"), notes(d / "out" / "notes.txt");
    std::string a, b;
    stats >> a;
    notes >> b;
    EXPECT_EQ(a, "new");
    EXPECT_EQ(b, "mine");
    std::size_t entries = 0;
    for (const auto& e : fs::directory_iterator(d)) entries += e.path().filename() != "out";
    EXPECT_EQ(entries, 0u) << "a staging folder was left behind";
}

} // namespace
} // namespace vox
