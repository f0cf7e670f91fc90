#pragma once
// What tests of every module share: folders for the files a test writes, and checks of the
// InputError messages that bad input must produce.

#include <filesystem>
#include <functional>
#include <string>
#include <vector>

namespace vox::test {

/// An empty folder `name` in gtest's temporary folder, emptied first when it exists; it is left
/// in place afterwards, for a look at what the test wrote.
[[nodiscard]] std::filesystem::path fresh_dir(const std::string& name);

/// An empty folder of the running test's own (named after its suite, name and process), removed
/// with everything in it when the ScratchDir goes. Construct it while the test runs (a fixture
/// member or a test's local).
class ScratchDir {
public:
    ScratchDir();
    ~ScratchDir();
    ScratchDir(const ScratchDir&) = delete;
    ScratchDir& operator=(const ScratchDir&) = delete;

    /// The folder itself.
    [[nodiscard]] const std::filesystem::path& root() const { return m_root; }
    /// The path of `name` in the folder, as a string.
    [[nodiscard]] std::string path(const std::string& name) const;
    /// Writes `bytes` to `name` in the folder and returns its path.
    std::string write(const std::string& name, const std::string& bytes) const;

private:
    std::filesystem::path m_root;
};

/// Single-quotes `s` for the shell.
[[nodiscard]] std::string quote(const std::string& s);

/// Runs Debian's /usr/bin/python3 (the tests' independent readers and writers come from its
/// packages: pydicom, nibabel, meshio) on `script` with `args`, each quoted; its standard output
/// goes to `output` when given. Returns the exit status (0: it ran and succeeded).
int run_python(const std::string& script, const std::vector<std::string>& args, const std::string& output = "");

/// The message of the InputError `f` throws; adds a test failure and returns "" when it throws
/// none.
[[nodiscard]] std::string error_of(const std::function<void()>& f);

/// Expects `f` to throw an InputError whose message starts with `file` and contains `problem`.
void expect_refused(const std::function<void()>& f, const std::string& file, const std::string& problem);

} // namespace vox::test
