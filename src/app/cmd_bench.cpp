// voxsculpt bench: the benchmark harnesses (bench/harness) behind one subcommand each. Every
// bench writes to --out (default out/), never over the committed tables in docs/benchmarks, which
// are rendered from a bench's output on purpose.

#include "app/commands.hpp"
#include "bench/harness/compare.hpp"
#include "bench/harness/conditioning.hpp"
#include "bench/harness/cutting.hpp"
#include "bench/harness/drilling.hpp"
#include "bench/harness/glide.hpp"
#include "bench/harness/haptics.hpp"
#include "bench/harness/stability.hpp"
#include "bench/harness/tradeoff.hpp"
#include "bench/harness/two_levels.hpp"
#include "core/error.hpp"

#include <CLI/CLI.hpp>

#include <memory>
#include <optional>
#include <string>

namespace vox::app {

using namespace vox::bench;

void add_bench_command(CLI::App& app)
{
    CLI::App* bench = app.add_subcommand("bench", "Measure the product: speed against accuracy");
    bench->require_subcommand(1);
    auto out = std::make_shared<std::string>("out");
    auto skip_liver = std::make_shared<bool>(false);
    CLI::App* tradeoff = bench->add_subcommand(
        "tradeoff", "Cantilever vs Euler-Bernoulli and level 0, liver vs level 1: a table and an SVG plot");
    tradeoff->add_option("--out", *out, "Folder for tradeoff.md and tradeoff.svg (default out)");
    tradeoff->add_flag("--skip-liver", *skip_liver, "Only the beam (faster)");
    tradeoff->callback([out, skip_liver] { run_tradeoff(*out, !*skip_liver); });

    auto levels_out = std::make_shared<std::string>("out");
    auto levels_skip_liver = std::make_shared<bool>(false);
    CLI::App* levels = bench->add_subcommand(
        "levels", "Two levels (fine at the tools, coarse elsewhere) against the uniform fine and coarse levels, pressing and cutting a beam "
                  "and the liver: tables and SVG plots");
    levels->add_option("--out", *levels_out, "Folder for levels.md, levels.json and the plots (default out)");
    levels->add_flag("--skip-liver", *levels_skip_liver, "Only the beam (a minute; the liver takes several: its uniform level 2 takes seconds a frame)");
    levels->callback([levels_out, levels_skip_liver] { run_two_levels_bench(*levels_out, !*levels_skip_liver); });

    auto seconds = std::make_shared<double>(10.0);
    CLI::App* haptics = bench->add_subcommand("haptics", "Period error and force time of the 1 kHz loop beside a running simulation");
    haptics->add_option("--seconds", *seconds, "How long to run (default 10)")->check(CLI::Range(0.5, 3600.0));
    auto isxfem = std::make_shared<bool>(false);
    auto haptics_solver = std::make_shared<std::string>("dbg");
    auto devices = std::make_shared<int>(1);
    haptics->add_flag("--isxfem", *isxfem, "Simulate with the Is-XFEM solver (as --solver isxfem)");
    haptics->add_option("--solver", *haptics_solver, "The method simulating the scene: dbg (default), isxfem or shape_matching")
        ->check(CLI::IsMember({"dbg", "isxfem", "shape_matching"}));
    haptics->add_option("--devices", *devices, "Devices the loop serves at once: 1 (a knife) or 2 (a knife and a finger pressing together)")
        ->check(CLI::Range(1, 2));
    auto lockstep = std::make_shared<bool>(false);
    haptics->add_flag("--lockstep", *lockstep,
                      "No threads: the simulation and the ticks take turns in simulated time, the same ticks every run (force time only)");
    auto finger_subdivision = std::make_shared<int>(-1);
    haptics->add_option("--haptic-subdivision", *finger_subdivision,
                        "With --devices 2: the finger's haptic_subdivision, -1 (off, default) or 0 - 3, to time its contact patch")
        ->check(CLI::Range(-1, 3));
    auto knife_device = std::make_shared<std::string>("script");
    haptics->add_option("--device", *knife_device,
                        "What holds the knife: script (default), or a force-feedback device, openhaptics or forcedimension (docs/devices.md)")
        ->check(CLI::IsMember({"script", "openhaptics", "forcedimension"}));
    haptics->callback([seconds, isxfem, haptics_solver, devices, lockstep, finger_subdivision, knife_device] {
        if (*finger_subdivision >= 0 && *devices < 2)
            throw CLI::ValidationError("--haptic-subdivision", "times the finger's contact patch, and the finger is the second device: add --devices 2");
        if (*lockstep && *knife_device != "script")
            throw CLI::ValidationError("--lockstep", "ticks in simulated time, which a hand on a device does not keep: leave out --device");
        run_haptics_bench({*seconds, *isxfem ? io::SolverType::isxfem : io::solver_type_named(*haptics_solver), *devices, *lockstep,
                           *finger_subdivision, *knife_device});
    });

    auto glide_out = std::make_shared<std::string>("out");
    CLI::App* glide = bench->add_subcommand("glide", "The force's change per 1 kHz tick while a ball glides across a block, each method, two speeds");
    glide->add_option("--out", *glide_out, "Folder for glide.md and glide.json (default out)");
    glide->callback([glide_out] { run_glide_bench(*glide_out); });

    auto cutting_runs = std::make_shared<int>(3);
    auto cutting_out = std::make_shared<std::string>("out");
    CLI::App* cutting = bench->add_subcommand("cutting", "Cutting-frame time on the liver at level 4 during a 5 cm incision, Jacobi against Cholesky");
    cutting->add_option("--runs", *cutting_runs, "How many times to replay the incision with each preconditioner (default 3)")->check(CLI::Range(1, 100));
    cutting->add_option("--out", *cutting_out, "Folder for cutting.md and cutting.json (default out)");
    cutting->callback([cutting_runs, cutting_out] { run_cutting_bench(*cutting_runs, *cutting_out); });

    auto drilling_runs = std::make_shared<int>(3);
    auto drilling_out = std::make_shared<std::string>("out");
    CLI::App* drilling = bench->add_subcommand("drilling", "Whole-frame time while a burr drills the CT-like skull, elastic against rigid bone");
    drilling->add_option("--runs", *drilling_runs, "How many times to drill each (default 3)")->check(CLI::Range(1, 100));
    drilling->add_option("--out", *drilling_out, "Folder for drilling.md and drilling.json (default out)");
    drilling->callback([drilling_runs, drilling_out] { run_drilling_bench(*drilling_runs, *drilling_out); });

    auto conditioning_out = std::make_shared<std::string>("out");
    CLI::App* conditioning = bench->add_subcommand(
        "conditioning", "Condition numbers of XFEM and Is-XFEM systems as a cut nears a node plane, with and without preconditioning");
    conditioning->add_option("--out", *conditioning_out, "Folder for conditioning.md (default out)");
    conditioning->callback([conditioning_out] { write_conditioning(*conditioning_out, run_conditioning()); });

    struct CompareArgs {
        std::string scene, out = "out";
        std::optional<int> frames;
    };
    auto compare_args = std::make_shared<CompareArgs>();
    CLI::App* compare = bench->add_subcommand(
        "compare", "The same scene and tool script by the branched grid and by Is-XFEM (k = 0.1 and k = 0), side by side");
    compare->add_option("scene", compare_args->scene, "Scene file (.json)")->required();
    compare->add_option("--frames", compare_args->frames, "Number of frames (default: the script's duration / dt_s, else 100)")
        ->check(CLI::PositiveNumber);
    compare->add_option("--out", compare_args->out, "Folder for compare-SCENE.md (default out)");
    compare->callback([compare_args] { run_compare(compare_args->scene, compare_args->frames, compare_args->out); });

    auto stability_out = std::make_shared<std::string>("out");
    auto quick = std::make_shared<bool>(false);
    CLI::App* stability = bench->add_subcommand(
        "stability", "The solver at the extremes (Poisson ratio, stiffness, time step, 1/512 fill, twist, inversion, 100 N kick)");
    stability->add_option("--out", *stability_out, "Folder for stability.md and stability.json (default out)");
    stability->add_flag("--quick", *quick, "A short beam only, few steps (the test suite's subset)");
    stability->callback([stability_out, quick] {
        const std::vector<StabilityResult> results = run_stability(*quick);
        write_stability(*stability_out, results);
        for (const StabilityResult& r : results)
            if (r.outcome == "diverged") throw InputError("bench stability: " + r.object + ", " + r.variation + ": diverged (" + r.detail + ")");
    });
}

} // namespace vox::app
