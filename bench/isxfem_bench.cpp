// Is-XFEM speed benchmark: the whole frame of a blade stroke, as a user's session runs it, through
// the simulation core (sim/frame_loop.hpp): the blade's contact with the closed surface, the cut
// along its swept surface where the pressure at its edge holds, the surface closed along the new
// crack, and the step. A block of 9,720 tetrahedra (40 x 18 x 18 mm of 1 mm voxels at level 1:
// 20 x 9 x 9 cells of 2 mm, six tetrahedra each; E 100 kPa, nu 0.3, 1500 kg/m^3), held at one end
// under gravity, cut across its middle by a blade going down through it over 20 frames, then
// drawn out, the pieces falling apart; dt 0.01 s, CG to 1e-6, warped factor or Jacobi.
// Reports per frame (tools and step, wall clock): median, p95 and max, the rate at the median, the
// medians of the frames the blade cut in and of those after, of the tools' part (contact, cut,
// closure) and of the step's update and solve, CG iterations, and the tetrahedra cut. The target:
// a 10,000-tetrahedron object being cut at 100 Hz or better on 2 cores.
// Usage: vox_isxfem_bench [FRAMES] [THREADS] (defaults 60 and 1); VOX_BENCH_FACTOR_ONLY=1 skips the
// Jacobi run.

#include "bench/bench_stats.hpp"
#include "core/stopwatch.hpp"
#include "io/scene.hpp"
#include "io/scene_object.hpp"
#include "sim/frame_loop.hpp"
#include "sim/isxfem_method.hpp"

#include <tbb/global_control.h>

#include <cstdio>
#include <cstdlib>

using namespace vox;

namespace {

io::Scene block_scene(const char* preconditioner)
{
    // The blade's edge starts on the top face (z = 17.5 mm) and goes 23.8 mm down in 0.2 s, to
    // 6 mm below the bottom face (the soft block, held at one end, gives way under it by several
    // mm: an edge stopping 2 mm below the face left the last row of cells uncut), crossing the
    // block at x = 20.1 mm, between two node planes; then it is drawn out sideways (along its
    // own plane, 0.05 s) and the pieces fall on their own.
    auto pose = [](double t, double y, double z) {
        return nlohmann::json{{"t_s", t}, {"tool", "blade"}, {"position_mm", {20.1, y, z}}, {"orientation_wxyz", {0.7071068, 0, 0, 0.7071068}}};
    };
    const nlohmann::json blade_pose0 = pose(0.0, 8.5, 37.5), blade_pose1 = pose(0.2, 8.5, 13.7), blade_pose2 = pose(0.25, 100.0, 13.7);
    const nlohmann::json document{
        {"object", {{"phantom", {{"shape", "block"}, {"size_mm", {40, 18, 18}}}}, {"levels", 1}}},
        {"materials", {{"default", {{"youngs_modulus_pa", 1e5}, {"poisson_ratio", 0.3}, {"density_kg_m3", 1500}}}}},
        {"solver", {{"type", "isxfem"}, {"dt_s", 0.01}, {"cg_tolerance", 1e-6}, {"cg_max_iterations", 5000}, {"rayleigh_mass_per_s", 0.5},
                    {"rayleigh_stiffness_s", 0.002}, {"preconditioner", preconditioner}}},
        {"gravity_m_s2", {0, 0, -9.81}},
        {"constraints", {{{"type", "fixed"}, {"box_mm", {{-1, -1, -1}, {0, 19, 19}}}}}},
        {"tools", {{{"name", "blade"}, {"shape", "blade"}, {"size_mm", {60, 1, 40}}, {"push_margin_mm", 0.25}, {"cut_pressure_pa", 5e3}}}},
        {"script", {blade_pose0, blade_pose1, blade_pose2}}};
    return io::parse_scene(document, std::filesystem::current_path(), "isxfem bench block");
}

double p95(std::vector<double> v) { return quantile(std::move(v), 0.95); }

void run(bool factor, int frames)
{
    const io::Scene scene = block_scene(factor ? "cholesky" : "jacobi");
    sim::IsxfemMethod method(scene, std::make_shared<const grid::LabelGrid>(io::load_scene_object(scene)), scene.object.levels);
    sim::ToolPolicy tools(scene);
    sim::FrameLoop loop(scene, method, tools);
    std::vector<double> frame_ms, cutting_ms, after_ms, tools_ms, update_ms, solve_ms, its;
    std::size_t cut_tets = 0;
    bool cut_begun = false;
    for (int f = 1; f <= frames; ++f) {
        Stopwatch clock;
        const sim::FrameStats s = loop.next();
        const double ms = clock.lap();
        frame_ms.push_back(ms);
        const bool cutting = s.tools.cut.changed();
        cut_begun = cut_begun || cutting;
        if (cutting) cutting_ms.push_back(ms);
        else if (cut_begun) after_ms.push_back(ms);
        tools_ms.push_back(ms - s.step.step_ms);
        update_ms.push_back(s.step.assembly_ms);
        solve_ms.push_back(s.step.solve_ms);
        its.push_back(s.step.cg_iterations);
        cut_tets += s.tools.cut.cut_elements;
    }
    const bench::Summary fs = bench::summarize(frame_ms);
    std::printf("| %s | %zu | %zu | %.2f ms | %.2f ms | %.2f ms | %.0f Hz | %zu: %.2f ms | %.2f ms | %.2f ms | %.2f ms | %.2f ms | %.0f | %zu | %zu | %s |\n",
                factor ? "warped Cholesky" : "Jacobi", method.element_count(), method.dof_count(), fs.median, p95(frame_ms), fs.max,
                1000.0 / fs.median, cutting_ms.size(), bench::summarize(cutting_ms).median, bench::summarize(after_ms).median,
                bench::summarize(tools_ms).median, bench::summarize(update_ms).median, bench::summarize(solve_ms).median,
                bench::summarize(its).median, cut_tets, method.piece_count(), method.linear_solver().c_str());
    std::fflush(stdout);
}

} // namespace

int main(int argc, char** argv)
{
    const int frames = argc > 1 ? std::max(22, std::atoi(argv[1])) : 60;
    const int threads = argc > 2 ? std::max(1, std::atoi(argv[2])) : 1;
    const tbb::global_control limit(tbb::global_control::max_allowed_parallelism, static_cast<std::size_t>(threads));
    std::printf("machine: %s; %d thread%s; %d frames\n\n", bench::machine().c_str(), threads, threads > 1 ? "s" : "", frames);
    std::printf("| preconditioner | tetrahedra | final DOFs | frame (median) | p95 | max | rate at the median | cutting frames: median | "
                "frames after the cut (median) | tools: contact, cut, closure (median) | update (median) | solve (median) | "
                "CG iterations (median) | tetrahedra cut | pieces | linear solver |\n"
                "|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|\n");
    run(true, frames);
    if (!std::getenv("VOX_BENCH_FACTOR_ONLY")) run(false, frames);
    return 0;
}
