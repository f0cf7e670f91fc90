// FEM step benchmark:
//  - the bundled liver (label 255; E 30 kPa, nu 0.45, 1060 kg/m^3, held above y = 185 mm, gravity
//    along +y), implicit Euler dt 0.01 s, CG to 1e-6 relative, at levels 2 to 5 with the multigrid,
//    warped Cholesky and matrix-free Jacobi preconditioners: elements, degrees of freedom, step time
//    (assembly + solve + energy check), CG iterations;
//  - the 75 x 15 x 15-element beam of SOFA's HexahedronFEMForceField comparison as a level-0 model
//    (1 mm voxels, clamped at x = 0, gravity), dt 0.04 s, CG capped at 10 iterations.
// Each case runs a few warm-up steps, then RUNS timed steps (median and spread).
// Usage: vox_fem_bench [RUNS] [THREADS] (defaults 20 and 1). Prints Markdown tables for the README.
// VOX_BENCH_BEAM_ONLY=1: only the beam; VOX_BENCH_QUICK=1: the liver at levels 5 and 4 only.

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

using namespace vox;

namespace {

struct Row {
    std::size_t elements = 0, dofs = 0;
    bench::Summary step, assembly, solve;
    double iterations = 0.0;
};

/// Steps `solver` `warmup` times, then `runs` timed times.
Row measure(const fem::HexModel& model, fem::ImplicitSolver& solver, int warmup, int runs)
{
    for (int i = 0; i < warmup; ++i) solver.step();
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
    return r;
}

void print(const char* what, const Row& r)
{
    std::printf("| %s | %zu | %zu | %.2f ms | %.2f - %.2f ms | %.2f ms | %.2f ms | %.0f |\n", what, r.elements, r.dofs,
                r.step.median, r.step.min, r.step.max, r.assembly.median, r.solve.median, r.iterations);
    std::fflush(stdout);
}

/// The liver at levels 5 to 2 with each preconditioner worth measuring there.
void liver_rows(int runs, bool quick)
{
    io::Selection selection;
    selection.labels = {255};
    const grid::LabelGrid liver = io::select_voxels(io::read_volume(VOX_SOURCE_DIR "/data/liver.inr.gz"), selection);
    const std::vector<grid::VoxelMaterial> tissue{{grid::lame_from_young_poisson(3e4, 0.45), 1060.0}};
    const grid::BranchedGrid g(grid::FineVoxels(liver, [](std::int32_t) { return 0; }), tissue, 6);
    enum { multigrid, cholesky, jacobi };
    const char* const names[] = {"multigrid", "warped Cholesky", "Jacobi, matrix-free"};
    for (int level = 5; level >= (quick ? 4 : 2); --level)
        for (int pc : {multigrid, cholesky, jacobi}) {
            // Level 2 (186 k DOFs): Jacobi takes seconds a step and the factor gigabytes.
            if (level == 2 && pc != multigrid) continue;
            const fem::HexModel model(g, level);
            fem::SolverOptions o;
            o.dt_s = 0.01;
            o.cg_tolerance = 1e-6;
            o.cg_max_iterations = 10000;
            o.rayleigh_mass_per_s = 0.5;
            o.rayleigh_stiffness_s = 0.002;
            o.matrix_free = pc == jacobi;
            fem::ImplicitSolver solver(model, o);
            if (pc == multigrid) solver.set_preconditioner(std::make_unique<fem::Multigrid>(g, model, 6));
            if (pc == cholesky) solver.set_preconditioner(std::make_unique<fem::RestCholesky>(model.frame()));
            solver.set_gravity({0, 9.81, 0});
            for (std::uint32_t n = 0; n < model.node_count(); ++n)
                if (model.rest_positions()[n].y() >= 0.185) solver.fix(n, 7);
            char what[64];
            std::snprintf(what, sizeof what, "liver, level %d, CG to 1e-6, %s", level, names[pc]);
            print(what, measure(model, solver, 5, level <= 2 ? std::min(runs, 5) : runs));
        }
}

/// The SOFA comparison beam, assembled and matrix-free.
void beam_rows(int runs)
{
    grid::PhantomSpec beam = grid::default_phantom(grid::PhantomShape::beam);
    beam.size_mm = {75, 15, 15};
    const std::vector<grid::VoxelMaterial> rubber{{grid::lame_from_young_poisson(1e6, 0.45), 1000.0}};
    const grid::BranchedGrid bg(grid::FineVoxels(grid::make_phantom(beam), [](std::int32_t) { return 0; }), rubber, 1);
    const fem::HexModel model(bg, 0);
    for (bool matrix_free : {false, true}) {
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
    const int runs = argc > 1 ? std::max(1, std::atoi(argv[1])) : 20;
    const int threads = argc > 2 ? std::max(1, std::atoi(argv[2])) : 1;
    const tbb::global_control limit(tbb::global_control::max_allowed_parallelism, static_cast<std::size_t>(threads));
    std::printf("machine: %s; %d thread%s\n\n", bench::machine().c_str(), threads, threads > 1 ? "s" : "");
    std::printf("| case | elements | DOFs | step (median) | min - max | assembly | solve | CG iterations |\n"
                "|---|---|---|---|---|---|---|---|\n");
    if (!std::getenv("VOX_BENCH_BEAM_ONLY")) liver_rows(runs, std::getenv("VOX_BENCH_QUICK") != nullptr);
    beam_rows(runs);
    return 0;
}
