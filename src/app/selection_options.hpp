#pragma once
// The --label / --threshold options shared by the subcommands that read volumes.

#include "io/selection.hpp"

#include <string>
#include <vector>

namespace CLI {
class App;
}

namespace vox::app {

struct SelectionOptions {
    std::vector<std::int32_t> labels;
    std::string threshold;
    /// Throws InputError when both are given or the threshold text is malformed.
    [[nodiscard]] io::Selection to_selection() const;
};

void add_selection_options(CLI::App& cmd, SelectionOptions& options);

/// Throws InputError unless `path` ends in .vdb.
void require_vdb_extension(const std::string& path);

} // namespace vox::app
