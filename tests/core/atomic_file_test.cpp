#include "core/atomic_file.hpp"
#include "core/error.hpp"
#include "test_support.hpp"

#include <gtest/gtest.h>

#include <fstream>

namespace fs = std::filesystem;
using vox::test::fresh_dir;

namespace {
std::size_t entries(const fs::path& d) { return static_cast<std::size_t>(std::distance(fs::directory_iterator(d), {})); }
} // namespace

TEST(AtomicFile, WritesThroughTemporaryThenRenames)
{
    const fs::path d = fresh_dir("atomic_ok");
    vox::write_atomically(d / "sub" / "out.txt", [](const fs::path& tmp) {
        EXPECT_NE(tmp.filename(), "out.txt");
        std::ofstream(tmp) << "hello";
    });
    std::ifstream in(d / "sub" / "out.txt");
    std::string s;
    in >> s;
    EXPECT_EQ(s, "hello");
    EXPECT_EQ(entries(d / "sub"), 1u); // no temporary left behind
}

TEST(AtomicFile, FailedWriteLeavesNothingAndKeepsOldFile)
{
    const fs::path d = fresh_dir("atomic_fail");
    std::ofstream(d / "out.txt") << "old";
    EXPECT_THROW(vox::write_atomically(d / "out.txt",
                                       [](const fs::path& tmp) {
                                           std::ofstream(tmp) << "half";
                                           throw vox::InputError("boom");
                                       }),
                 vox::InputError);
    std::ifstream in(d / "out.txt");
    std::string s;
    in >> s;
    EXPECT_EQ(s, "old");
    EXPECT_EQ(entries(d), 1u);
}
