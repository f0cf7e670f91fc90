// voxsculpt ccd-check: the continuous collision tests against a benchmark query file with ground
// truth (data/ccd-queries): counts of true and false positives and negatives. A conservative test
// has no false negatives; its false positives say how conservative it is.

#include "app/commands.hpp"
#include "contact/ccd_queries.hpp"

#include <CLI/CLI.hpp>

#include <cstdio>
#include <memory>

namespace vox::app {

void add_ccd_check_command(CLI::App& app)
{
    struct Args {
        std::string file, type;
    };
    auto args = std::make_shared<Args>();
    CLI::App* cmd = app.add_subcommand("ccd-check", "Score the continuous collision tests on a query file with ground truth");
    cmd->add_option("file", args->file, "Query file (.csv, the format of data/ccd-queries)")->required();
    cmd->add_option("--type", args->type, "vf (vertex-face) or ee (edge-edge)")->required()->check(CLI::IsMember({"vf", "ee"}));
    cmd->callback([args] {
        const auto queries = contact::read_ccd_queries(args->file);
        const contact::CcdScore s = contact::score_ccd(queries, args->type == "vf");
        std::printf("true_positives: %zu false_positives: %zu false_negatives: %zu true_negatives: %zu\n", s.true_positives,
                    s.false_positives, s.false_negatives, s.true_negatives);
    });
}

} // namespace vox::app
