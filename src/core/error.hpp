#pragma once
// Errors raised at API boundaries. The program turns each into one line on stderr and an exit code.

#include <stdexcept>
#include <string>

namespace vox {

/// Bad input from the user: a malformed or missing file, an absurd parameter, an empty selection.
/// The message names the thing (file path or key path) and the problem; the program exits with 2.
class InputError : public std::runtime_error {
public:
    explicit InputError(const std::string& message) : std::runtime_error(message) {}
};

/// Builds "PATH: what" so every message about a file starts with the file's name.
[[nodiscard]] InputError file_error(const std::string& path, const std::string& what);

} // namespace vox
