// Is-XFEM step benchmark: a block of about 10,000 tetrahedra (20 x 9 x 9 cubes of 2 mm, six
// tetrahedra each: 9,720; E 100 kPa, nu 0.3, 1500 kg/m^3), held at one end under gravity, cut
// across its middle by a blade going down through its 18 mm over 20 frames, then falling apart;
// dt 0.01 s, CG to 1e-6, with the warped factor
// and with Jacobi. Per frame: cut update (the tetrahedra the blade has crossed whole) plus the step.
// Reports median, 95th percentile and max frame time, the frame rate that median gives, the
// medians of the frames the blade cut in (the factor kept and the cut patched) and of those after,
// of the step's update (rotations, forces, matrix) and solve, and the CG iterations. The target: a 10,000-tetrahedron object being cut at 100 Hz or better on
// 2 cores. The note counts the factorisations, those taken in the background (off the frame:
// fem/rest_cholesky.hpp) and the frames that had to wait for one.
// Usage: vox_isxfem_bench [FRAMES] [THREADS] (defaults 60 and 1); VOX_BENCH_FACTOR_ONLY=1 skips the
// Jacobi run.

#include "bench/bench_stats.hpp"
#include "fem/rest_cholesky.hpp"
#include "isxfem/xfem_solver.hpp"

#include <tbb/global_control.h>

#include <chrono>
#include <cstdio>
#include <cstdlib>

using namespace vox;

namespace {

void run(bool factor, int frames)
{
    constexpr double h = 0.002;
    isxfem::TetMesh block = isxfem::cube_lattice({20, 9, 9}, h);
    const std::size_t tets = block.tets.size();
    isxfem::XfemModel model(std::move(block), {isxfem::TetMaterial{grid::lame_from_young_poisson(1e5, 0.3), 1500.0}},
                            std::vector<std::uint32_t>(tets, 0), 0.1);
    isxfem::XfemOptions o;
    o.dt_s = 0.01;
    o.cg_tolerance = 1e-6;
    o.cg_max_iterations = 5000;
    o.rayleigh_mass_per_s = 0.5;
    o.rayleigh_stiffness_s = 0.002;
    isxfem::XfemSolver solver(model, o);
    const fem::RestCholesky* warped = nullptr;
    if (factor) {
        auto p = std::make_unique<fem::RestCholesky>(Eigen::Matrix3d::Identity());
        warped = p.get();
        solver.set_preconditioner(std::move(p));
    }
    solver.set_gravity({0, 0, -9.81});
    for (std::size_t n = 0; n < model.node_count(); ++n)
        if (model.mesh().nodes[n].x() < 1e-9) solver.fix(static_cast<std::uint32_t>(n), 7);
    const isxfem::PlaneCut plane{Eigen::Vector3d::UnitX(), 10.3 * h};
    const double top = 9 * h;
    int cut = -1;
    std::vector<double> frame_ms, cutting_ms, after_ms, update_ms, solve_ms, its;
    for (int f = 1; f <= frames; ++f) {
        const auto start = std::chrono::steady_clock::now();
        const double depth = std::min(1.0, f / 20.0) * 1.1 * top; // the blade's edge goes down to below the block
        bool cutting = false;
        if (f <= 22) {
            const isxfem::CutReport r = model.cut(plane, [&](const Eigen::Vector3d& p) { return p.z() >= top - depth; }, cut);
            if (r.cut >= 0) cut = r.cut;
            if (r.cut_tets > 0) solver.model_changed();
            cutting = r.cut_tets > 0;
        }
        const double c = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
        const isxfem::XfemStepStats s = solver.step();
        frame_ms.push_back(c + s.step_ms);
        (cutting ? cutting_ms : after_ms).push_back(c + s.step_ms);
        update_ms.push_back(s.assembly_ms);
        solve_ms.push_back(s.solve_ms);
        its.push_back(s.cg_iterations);
    }
    const bench::Summary fs = bench::summarize(frame_ms);
    std::vector<double> sorted = frame_ms;
    std::sort(sorted.begin(), sorted.end());
    const double p95 = sorted[static_cast<std::size_t>(0.95 * static_cast<double>(sorted.size() - 1))];
    char note[200] = "";
    if (warped)
        std::snprintf(note, sizeof note, "%d factorisations (%d in the background; frames that waited for one: %d); solves in %zu parallel groups, serial top %.0f %%",
                      warped->factorizations(), warped->background_factorizations(), warped->frames_waited(), warped->factor().parallel_groups(),
                      100.0 * warped->factor().top_share());
    if (!solver.fallback_note().empty()) std::snprintf(note, sizeof note, "%s", solver.fallback_note().c_str());
    std::printf("| %s | %zu | %zu | %.2f ms | %.2f ms | %.2f ms | %.0f Hz | %.2f ms | %.2f ms | %.2f ms | %.2f ms | %.0f | %s |\n",
                factor ? "warped Cholesky" : "Jacobi", tets, solver.dof_count(), fs.median, p95, fs.max, 1000.0 / fs.median,
                bench::summarize(cutting_ms).median, bench::summarize(after_ms).median, bench::summarize(update_ms).median,
                bench::summarize(solve_ms).median, bench::summarize(its).median, note);
    std::fflush(stdout);
}

} // namespace

int main(int argc, char** argv)
{
    const int frames = argc > 1 ? std::max(22, std::atoi(argv[1])) : 60;
    const int threads = argc > 2 ? std::max(1, std::atoi(argv[2])) : 1;
    const tbb::global_control limit(tbb::global_control::max_allowed_parallelism, static_cast<std::size_t>(threads));
    std::printf("machine: %s; %d thread%s; %d frames\n\n", bench::machine().c_str(), threads, threads > 1 ? "s" : "", frames);
    std::printf("| preconditioner | tetrahedra | final DOFs | frame (median) | p95 | max | rate at the median | cutting frames (median) | "
                "frames after the cut (median) | update (median) | solve (median) | CG iterations (median) | note |\n"
                "|---|---|---|---|---|---|---|---|---|---|---|---|---|\n");
    run(true, frames);
    if (!std::getenv("VOX_BENCH_FACTOR_ONLY")) run(false, frames);
    return 0;
}
