#include "app/run_command.hpp"

#include <gtest/gtest.h>
#include <sys/wait.h>

#include <atomic>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>

namespace vox::test {
namespace {
std::string slurp(const std::filesystem::path& p)
{
    std::ifstream in(p, std::ios::binary);
    std::stringstream ss;
    ss << in.rdbuf();
    return ss.str();
}
} // namespace

CommandResult run_voxsculpt(const std::string& args)
{
    static std::atomic<int> counter{0};
    const auto base = std::filesystem::temp_directory_path() /
                      ("voxsculpt-test-" + std::to_string(::getpid()) + "-" + std::to_string(counter++));
    const std::string cmd = quote(VOX_VOXSCULPT_EXE) + " " + args + " </dev/null >" + quote(base.string() + ".out") +
                            " 2>" + quote(base.string() + ".err");
    const int status = std::system(cmd.c_str());
    CommandResult r;
    r.exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
    r.out = slurp(base.string() + ".out");
    r.err = slurp(base.string() + ".err");
    std::filesystem::remove(base.string() + ".out");
    std::filesystem::remove(base.string() + ".err");
    return r;
}

nlohmann::json info_json(const std::filesystem::path& file)
{
    const CommandResult r = run_voxsculpt("info --json " + quote(file.string()));
    EXPECT_EQ(r.exit_code, 0) << r.err;
    return nlohmann::json::parse(r.out);
}

} // namespace vox::test
