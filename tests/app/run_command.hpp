#pragma once
// Runs the voxsculpt program the way a user does and captures what it printed.

#include "test_support.hpp" // quote()

#include <nlohmann/json.hpp>

#include <filesystem>
#include <string>

namespace vox::test {

struct CommandResult {
    int exit_code = -1;
    std::string out; ///< standard output
    std::string err; ///< standard error
};

/// Runs `voxsculpt ARGS` (ARGS is shell-quoted by the caller) with stdin from /dev/null.
CommandResult run_voxsculpt(const std::string& args);

/// What `voxsculpt info --json FILE` reports (a failed run is a test failure).
nlohmann::json info_json(const std::filesystem::path& file);

} // namespace vox::test
