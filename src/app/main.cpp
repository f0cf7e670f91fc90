// voxsculpt: the command-line program. Exit codes: 0 success, 2 bad input or usage, 1 internal error.

#include "app/commands.hpp"
#include "core/error.hpp"
#include "core/log.hpp"
#include "core/memory_limit.hpp"
#include "core/version.hpp"

#include <CLI/CLI.hpp>

#include <cstdio>
#include <exception>

int main(int argc, char** argv)
{
    CLI::App app{"VoxSculpt: physics-based sculpting and cutting of volumetric objects"};
    app.set_version_flag("--version", vox::program_version());
    app.require_subcommand(1);
    app.fallthrough(); // global options may follow the subcommand's own
    app.add_flag_callback("-q,--quiet", [] { vox::log::set_verbosity(vox::log::Verbosity::quiet); },
                          "Print only errors");
    app.add_flag_callback("-v,--verbose", [] { vox::log::set_verbosity(vox::log::Verbosity::verbose); },
                          "Print debugging detail");
    app.add_option_function<std::uint64_t>(
           "--max-memory-mb", [](std::uint64_t mb) { vox::set_memory_limit_bytes(mb << 20); },
           "Refuse inputs that would need more memory than this (default 8192, or $VOXSCULPT_MAX_MEMORY_MB)")
        ->check(CLI::Validator(
            [](const std::string& text) {
                return text.find_first_not_of("0123456789") == std::string::npos && text.find_first_not_of('0') != std::string::npos
                           ? std::string()
                           : std::string("must be a positive whole number of MiB");
            },
            "MiB"));

    vox::app::add_import_command(app);
    vox::app::add_info_command(app);
    vox::app::add_phantom_command(app);
    vox::app::add_check_command(app);
    vox::app::add_grid_command(app);
    vox::app::add_export_command(app);
    vox::app::add_run_command(app);
    vox::app::add_bench_command(app);
    vox::app::add_ccd_check_command(app);
    vox::app::add_devices_command(app);
    vox::app::add_render_command(app);
    vox::app::add_view_command(app);

    try {
        vox::check_memory_limit_environment();
        // CLI11 would report an unknown first word as a missing subcommand; say what is wrong.
        if (argc > 1 && argv[1][0] != '-') {
            bool known = false;
            for (const CLI::App* sub : app.get_subcommands([](const CLI::App*) { return true; }))
                known = known || sub->get_name() == argv[1];
            if (!known) {
                std::fprintf(stderr, "voxsculpt: unknown subcommand '%s' (see --help)\n", argv[1]);
                return 2;
            }
        }
        app.parse(argc, argv);
    } catch (const CLI::Success& e) {
        return app.exit(e);
    } catch (const CLI::ParseError& e) {
        std::fprintf(stderr, "voxsculpt: %s (see --help)\n", e.what());
        return 2;
    } catch (const vox::InputError& e) {
        std::fprintf(stderr, "voxsculpt: %s\n", e.what());
        return 2;
    } catch (const std::bad_alloc&) {
        std::fprintf(stderr, "voxsculpt: out of memory\n");
        return 1;
    } catch (const std::exception& e) {
        std::fprintf(stderr, "voxsculpt: internal error: %s\n", e.what());
        return 1;
    }
    return 0;
}
