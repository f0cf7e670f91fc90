#pragma once
// A run's outputs written into a hidden folder beside their destination and moved into it only
// when the run completes: a run that fails leaves nothing behind (no empty folder, no partial
// frames), and one that succeeds replaces the files of the same names.

#include <filesystem>

namespace vox {

class StagingDir {
public:
    /// Makes `.NAME.partial-PID` beside `destination`. Throws InputError when it cannot be made.
    explicit StagingDir(std::filesystem::path destination);
    StagingDir(const StagingDir&) = delete;
    StagingDir& operator=(const StagingDir&) = delete;
    /// Removes the staging folder and what is in it, unless commit() moved it.
    ~StagingDir();

    /// Where to write.
    [[nodiscard]] const std::filesystem::path& path() const { return m_staging; }
    /// Moves every file into the destination (made when missing), replacing files of the same
    /// names, and removes the staging folder. Throws InputError when a file cannot be moved.
    void commit();

private:
    std::filesystem::path m_destination, m_staging;
    bool m_committed = false;
};

} // namespace vox
