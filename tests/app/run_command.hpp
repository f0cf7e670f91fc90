#pragma once
// Runs the voxsculpt program the way a user does and captures what it printed.

#include <string>

namespace vox::test {

struct CommandResult {
    int exit_code = -1;
    std::string out; ///< standard output
    std::string err; ///< standard error
};

/// Runs `voxsculpt ARGS` (ARGS is shell-quoted by the caller) with stdin from /dev/null.
CommandResult run_voxsculpt(const std::string& args);

/// Single-quotes `s` for the shell.
std::string quote(const std::string& s);

} // namespace vox::test
