#include "app/selection_options.hpp"

#include "core/error.hpp"

#include <CLI/CLI.hpp>

namespace vox::app {

io::Selection SelectionOptions::to_selection() const
{
    if (!labels.empty() && !threshold.empty()) throw InputError("--label and --threshold cannot be combined");
    if (!threshold.empty()) return io::parse_threshold(threshold);
    io::Selection s;
    s.labels = labels;
    return s;
}

void add_selection_options(CLI::App& cmd, SelectionOptions& options)
{
    cmd.add_option("--label", options.labels, "Keep voxels with these stored labels (comma-separated)")
        ->delimiter(',');
    cmd.add_option("--threshold", options.threshold,
                   "Keep voxels whose scaled value (e.g. Hounsfield units) is in LO[:HI], inclusive; label 1");
}

void require_vdb_extension(const std::string& path)
{
    if (path.size() < 4 || path.compare(path.size() - 4, 4, ".vdb") != 0)
        throw InputError(path + ": the output must be an OpenVDB file ending in .vdb");
}

} // namespace vox::app
