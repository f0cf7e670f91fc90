#pragma once
// The voxsculpt subcommands. Each registers itself on the program's CLI11 app; its callback runs
// after parsing and reports bad input by throwing vox::InputError (exit code 2).

namespace CLI {
class App;
}

namespace vox::app {

void add_import_command(CLI::App& app);
void add_info_command(CLI::App& app);
void add_phantom_command(CLI::App& app);
void add_check_command(CLI::App& app);
void add_grid_command(CLI::App& app);
void add_export_command(CLI::App& app);
void add_run_command(CLI::App& app);
void add_bench_command(CLI::App& app);
void add_ccd_check_command(CLI::App& app);
void add_devices_command(CLI::App& app);
void add_render_command(CLI::App& app);
void add_view_command(CLI::App& app);

} // namespace vox::app
