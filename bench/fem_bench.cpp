// FEM step benchmark:
//  - the bundled liver (label 255; E 30 kPa, nu 0.45, 1060 kg/m^3, gravity along +y), implicit
//    Euler dt 0.01 s, CG to 1e-6 relative, from rest: the sag, the sway and the settling that
//    follow. Held at its back (y >= 100 mm, as in liver_incision.json) at levels 2 to 5 with the
//    multigrid, warped Cholesky and matrix-free Jacobi preconditioners; and, as a stress case,
//    hanging from its top (y >= 185 mm, as in liver.json: it stretches and swings by up to half a
//    metre) at level 4. Elements, degrees of freedom, step time (assembly + solve + energy check:
//    median, spread, and the mean, which carries the occasional refactorisation), CG iterations;
//  - the 75 x 15 x 15-element beam of SOFA's HexahedronFEMForceField comparison as a level-0 model
//    (1 mm voxels, clamped at x = 0, gravity), dt 0.04 s, CG capped at 10 iterations.
// Each case runs 5 warm-up steps (3 for the beam), then RUNS timed steps (20 at level 3, 5 at
// level 2).
// Usage: vox_fem_bench [RUNS] [THREADS] (defaults 100 and 1). Prints Markdown tables for the README.
// VOX_BENCH_BEAM_ONLY=1: only the beam (=matrix-free: only its matrix-free case, for profiling);
// VOX_BENCH_QUICK=1: the liver at levels 5 and 4 only.

#include "bench/bench_stats.hpp"
#include "fem/implicit_solver.hpp"
#include "fem/multigrid.hpp"
#include "fem/rest_cholesky.hpp"
#include "grid/hex8.hpp"
#include "grid/phantom.hpp"
#include "io/selection.hpp"
#include "io/volume_reader.hpp"

#include <tbb/global_control.h>

#include <cstdio>
#include <cstdlib>
#include <numeric>
#include <string_view>

using namespace vox;

namespace {

struct Row {
    std::size_t elements = 0, dofs = 0;
    bench::Summary step, assembly, solve;
    double mean_step = 0.0, iterations = 0.0;
    int factorizations = -1; ///< of the warped factor over the timed steps; -1: none used
};

/// Steps `solver` `warmup` times, then `runs` timed times.
Row measure(const fem::HexModel& model, fem::ImplicitSolver& solver, int warmup, int runs, const fem::RestCholesky* factor = nullptr)
{
    for (int i = 0; i < warmup; ++i) solver.step();
    const int factorizations = factor ? factor->factorizations() : 0;
    std::vector<double> step, assembly, solve;
    std::vector<double> its;
    for (int i = 0; i < runs; ++i) {
        const fem::StepStats s = solver.step();
        step.push_back(s.step_ms);
        assembly.push_back(s.assembly_ms);
        solve.push_back(s.solve_ms);
        its.push_back(s.cg_iterations);
    }
    Row r;
    r.elements = model.elements().size();
    r.dofs = solver.dof_count();
    r.step = bench::summarize(step);
    r.assembly = bench::summarize(assembly);
    r.solve = bench::summarize(solve);
    r.iterations = bench::summarize(its).median;
    r.mean_step = std::accumulate(step.begin(), step.end(), 0.0) / static_cast<double>(step.size());
    if (factor) r.factorizations = factor->factorizations() - factorizations;
    return r;
}

void print(const char* what, const Row& r)
{
    char factored[32] = "-";
    if (r.factorizations >= 0) std::snprintf(factored, sizeof factored, "%d", r.factorizations);
    std::printf("| %s | %zu | %zu | %.2f ms | %.2f - %.2f ms | %.2f ms | %.2f ms | %.2f ms | %.0f | %s |\n", what, r.elements,
                r.dofs, r.step.median, r.step.min, r.step.max, r.mean_step, r.assembly.median, r.solve.median, r.iterations, factored);
    std::fflush(stdout);
}

/// The liver at levels 5 to 2, held at its back, with each preconditioner worth measuring there;
/// then hanging from its top at level 4.
void liver_rows(int runs, bool quick)
{
    io::Selection selection;
    selection.labels = {255};
    const grid::LabelGrid liver = io::select_voxels(io::read_volume(VOX_SOURCE_DIR "/data/liver.inr.gz"), selection);
    const std::vector<grid::ElasticMaterial> tissue{{grid::lame_from_young_poisson(3e4, 0.45), 1060.0}};
    const grid::BranchedGrid g(grid::FineVoxels(liver, [](std::int32_t) { return 0; }), tissue, 6);
    enum { multigrid, cholesky, jacobi };
    const char* const names[] = {"multigrid", "warped Cholesky", "Jacobi, matrix-free"};
    auto row = [&](int level, int pc, double held_above_m, const char* support) {
        const fem::HexModel model(g, level);
        fem::SolverOptions o;
        o.dt_s = 0.01;
        o.cg_tolerance = 1e-6;
        o.cg_max_iterations = 10000;
        o.rayleigh_mass_per_s = 0.5;
        o.rayleigh_stiffness_s = 0.002;
        o.matrix_free = pc == jacobi;
        fem::ImplicitSolver solver(model, o);
        const fem::RestCholesky* factor = nullptr;
        if (pc == multigrid) solver.set_preconditioner(std::make_unique<fem::Multigrid>(g, model, 6));
        if (pc == cholesky) {
            auto p = std::make_unique<fem::RestCholesky>(model.frame());
            factor = p.get();
            solver.set_preconditioner(std::move(p));
        }
        solver.set_gravity({0, 9.81, 0});
        for (std::uint32_t n = 0; n < model.node_count(); ++n)
            if (model.rest_positions()[n].y() >= held_above_m) solver.fix(n, 7);
        char what[96];
        std::snprintf(what, sizeof what, "liver %s, level %d, %s", support, level, names[pc]);
        const int timed = level == 3 ? std::min(runs, 20) : level == 2 ? std::min(runs, 5) : runs;
        print(what, measure(model, solver, 5, timed, factor));
    };
    for (int level = 5; level >= (quick ? 4 : 2); --level)
        for (int pc : {multigrid, cholesky, jacobi})
            // Level 2 (186 k DOFs): Jacobi takes seconds a step and the factor gigabytes.
            if (level > 2 || pc == multigrid) row(level, pc, 0.100, "held at its back");
    for (int pc : {cholesky, jacobi}) row(4, pc, 0.185, "hanging from its top");
}

/// The SOFA comparison beam, assembled and matrix-free.
void beam_rows(int runs, bool matrix_free_only)
{
    grid::PhantomSpec beam = grid::default_phantom(grid::PhantomShape::beam);
    beam.size_mm = {75, 15, 15};
    const std::vector<grid::ElasticMaterial> rubber{{grid::lame_from_young_poisson(1e6, 0.45), 1000.0}};
    const grid::BranchedGrid bg(grid::FineVoxels(grid::make_phantom(beam), [](std::int32_t) { return 0; }), rubber, 1);
    const fem::HexModel model(bg, 0);
    for (bool matrix_free : {false, true}) {
        if (matrix_free_only && !matrix_free) continue;
        fem::SolverOptions o;
        o.dt_s = 0.04;
        o.cg_max_iterations = 10;
        o.matrix_free = matrix_free;
        fem::ImplicitSolver solver(model, o);
        solver.set_gravity({0, 0, -9.81});
        for (std::uint32_t n = 0; n < model.node_count(); ++n)
            if (model.rest_positions()[n].x() <= 1e-9) solver.fix(n, 7); // the face at x = -0.5 mm
        print(matrix_free ? "beam 75 x 15 x 15, level 0, CG capped at 10, matrix-free"
                          : "beam 75 x 15 x 15, level 0, CG capped at 10, assembled",
              measure(model, solver, 3, runs));
    }
}

} // namespace

int main(int argc, char** argv)
{
    const int runs = argc > 1 ? std::max(1, std::atoi(argv[1])) : 100;
    const int threads = argc > 2 ? std::max(1, std::atoi(argv[2])) : 1;
    const tbb::global_control limit(tbb::global_control::max_allowed_parallelism, static_cast<std::size_t>(threads));
    std::printf("machine: %s; %d thread%s\n\n", bench::machine().c_str(), threads, threads > 1 ? "s" : "");
    std::printf("| case | elements | DOFs | step (median) | min - max | mean | assembly | solve | CG iterations | factorisations |\n"
                "|---|---|---|---|---|---|---|---|---|---|\n");
    if (!std::getenv("VOX_BENCH_BEAM_ONLY")) liver_rows(runs, std::getenv("VOX_BENCH_QUICK") != nullptr);
    const char* beam_only = std::getenv("VOX_BENCH_BEAM_ONLY");
    beam_rows(runs, beam_only && std::string_view(beam_only) == "matrix-free");
    return 0;
}
