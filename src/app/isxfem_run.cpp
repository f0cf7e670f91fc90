#include "app/isxfem_run.hpp"

#include "app/isxfem_tools.hpp"
#include "app/isxfem_simulation.hpp"
#include "app/run_output.hpp"
#include "app/scene_simulation.hpp"
#include "core/atomic_file.hpp"
#include "core/error.hpp"
#include "core/log.hpp"
#include "core/progress.hpp"
#include "io/mesh_writer.hpp"
#include "io/scene_object.hpp"

#include <nlohmann/json.hpp>

#include <chrono>
#include <cmath>
#include <fstream>
#include <set>

namespace vox::app {
namespace {

void write_surface(const std::filesystem::path& path, const IsxfemSimulation& sim)
{
    const surface::SurfaceMesh m = sim.surface_mesh();
    io::write_mesh(path.string(), m.positions, m.triangles, m.labels);
}

} // namespace

void run_isxfem(const io::Scene& scene, const std::string& scene_path, std::optional<int> frame_count, const std::filesystem::path& out,
                ScenePictures* pictures, int render_every)
{
    if (scene.object.auto_levels) throw scene.error("object.levels", "\"isxfem\" needs a fixed level (0 to 6), not \"auto\"");
    const grid::LabelGrid labels = io::load_scene_object(scene);
    const int level = scene.object.levels;
    const grid::BranchedGrid g = build_scene_grid(scene, labels, std::max(level, 1));
    IsxfemSimulation sim(scene, g, level);
    IsxfemTools tools(scene);

    const double dt = scene.solver.dt_s;
    const double duration = scene.script.empty() ? 0.0 : scene.script.back().t_s;
    const int frames = frame_count.value_or(duration > 0 ? static_cast<int>(std::ceil(duration / dt)) : 100);
    std::filesystem::create_directories(out);
    log::info("{}: isxfem (k = {}), level {}, {} tetrahedra, {} degrees of freedom, {} frames of {} s", scene_path, scene.solver.isxfem_k,
              level, sim.tet_count(), sim.solver().dof_count(), frames, dt);
    nlohmann::json stats{{"scene", scene_path}, {"solver", "isxfem"}, {"k", scene.solver.isxfem_k},
                         {"regularisation", {{"lambda", scene.solver.isxfem_regularisation_lambda}, {"threshold", scene.solver.isxfem_regularisation_threshold}}},
                         {"level", level},
                         {"tetrahedra", sim.tet_count()}, {"dofs", sim.solver().dof_count()}, {"dt_s", dt},
                         {"linear_solver", std::string("CG, ") + sim.solver().preconditioner_name() + " preconditioner"}, {"frames", nlohmann::json::array()}};
    double total_ms = 0.0, max_ms = 0.0, cut_total_ms = 0.0;
    int converged = 0;
    std::size_t cut_tets = 0, partial = 0, recut = 0, crossed = 0, beside = 0;
    std::set<std::size_t> left_whole; // frames where a cut crossed tetrahedra already cut twice
    isxfem::XfemStepStats last;
    Progress progress("simulating", static_cast<std::uint64_t>(frames));
    const auto& rest = sim.model().mesh().nodes;
    for (int f = 1; f <= frames; ++f) {
        const auto cut_start = std::chrono::steady_clock::now();
        const IsxfemToolFrame tool_frame = tools.frame(sim, f, dt);
        const isxfem::CutReport& frame_cut = tool_frame.cut;
        const double cut_ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - cut_start).count();
        cut_total_ms += cut_ms;
        cut_tets += frame_cut.cut_tets;
        partial = frame_cut.partial_tets;
        recut += frame_cut.recut_tets;
        if (frame_cut.crossed_tets > 0 && crossed == 0)
            log::warn("frame {}: two cuts cross inside {} tetrahedra; the added enrichments cannot move their four pieces apart "
                      "independently, so the pieces stay coupled there (counted per frame in stats.json: crossed_tets; "
                      "orange in the pictures of --render-every)",
                      f, frame_cut.crossed_tets);
        crossed += frame_cut.crossed_tets;
        beside += frame_cut.beside_earlier;
        if (frame_cut.already_cut > 0) {
            // Two cuts per tetrahedron at most: a third leaves it as it was. Said once, counted
            // per frame in stats.json.
            if (left_whole.empty())
                log::warn("frame {}: {} tetrahedra already cut twice were crossed by another cut and left as they were (Is-XFEM "
                          "takes two cuts per tetrahedron; their pieces stay joined along the new cut; orange in the pictures "
                          "of --render-every)",
                          f, frame_cut.already_cut);
            left_whole.insert(static_cast<std::size_t>(f));
        }
        if (tool_frame.hold_object) { // a two-phase cut is being marked: the object is held, no step
            last.step_ms = last.assembly_ms = last.solve_ms = 0.0;
            last.cg_iterations = 0;
            last.residual = 0.0;
            last.converged = true;
        } else {
            last = sim.solver().step();
        }
        total_ms += last.step_ms;
        max_ms = std::max(max_ms, last.step_ms);
        converged += last.converged;
        if (!std::isfinite(last.kinetic_energy_j))
            throw InputError(scene_path + ": the simulation diverged at frame " + std::to_string(f) + " (non-finite energy); reduce solver.dt_s");
        double max_displacement = 0.0;
        for (std::size_t n = 0; n < rest.size(); ++n) max_displacement = std::max(max_displacement, (sim.solver().state()[n] - rest[n]).norm());
        stats["frames"].push_back({{"frame", f},
                                   {"t_s", f * dt},
                                   {"step_ms", last.step_ms},
                                   {"assembly_ms", last.assembly_ms},
                                   {"solve_ms", last.solve_ms},
                                   {"cut_ms", cut_ms},
                                   {"cg_iterations", last.cg_iterations},
                                   {"residual", last.residual},
                                   {"converged", last.converged},
                                   {"kinetic_energy_j", last.kinetic_energy_j},
                                   {"max_displacement_mm", max_displacement * 1e3},
                                   {"cut_tets", frame_cut.cut_tets},
                                   {"partly_crossed_tets", frame_cut.partial_tets},
                                   {"recut_tets", frame_cut.recut_tets},
                                   {"crossed_tets", frame_cut.crossed_tets},
                                   {"recut_tets_left", frame_cut.already_cut},
                                   {"beside_earlier_cut_tets", frame_cut.beside_earlier},
                                   {"dofs", sim.solver().dof_count()},
                                   {"regularised_blocks", sim.solver().regularised_blocks()},
                                   {"object_held", tool_frame.hold_object},
                                   {"tools", tool_frames_json(tool_frame.tools)}});
        if (f % scene.output.mesh_every_n_frames == 0) write_surface(out / frame_file_name(f, "obj"), sim);
        if (pictures && f % render_every == 0) pictures->write(out / frame_file_name(f, "png"), sim, tools, scene);
        progress.update(static_cast<std::uint64_t>(f));
    }
    progress.finish();
    stats["summary"] = step_summary(frames, total_ms, max_ms, converged);
    stats["summary"].update(
        {{"cut_tets", cut_tets},
         {"cuts", sim.model().cut_count()},
         {"partly_crossed_tets_last_frame", partial},
         {"recut_tets", recut},
         {"crossed_tets", crossed},
         {"beside_earlier_cut_tets", beside},
         {"frames_with_recut_tets_left", left_whole.size()},
         {"total_cut_ms", cut_total_ms},
         {"final_dofs", sim.solver().dof_count()},
         {"final_kinetic_energy_j", last.kinetic_energy_j}});
    const isxfem::ClosureCounts closure = sim.closure_counts();
    stats["summary"].update({{"crack_faces", closure.faces}, {"slit_faces", closure.slit_faces}, {"open_crack_chains", closure.open_chains}});
    if (closure.open_chains > 0)
        log::warn("{} run(s) of the cut surface could not be closed along their crack: the exported surface has holes there", closure.open_chains);
    if (!sim.solver().fallback_note().empty()) {
        log::warn("{}", sim.solver().fallback_note());
        stats["linear_solver"] = sim.solver().fallback_note();
    }
    write_surface(out / "final.obj", sim);
    if (pictures) pictures->write(out / "final.png", sim, tools, scene);
    write_atomically(out / "stats.json", [&](const std::filesystem::path &tmp) {
      std::ofstream(tmp) << stats.dump(1) << '\n';
    });
    log::info("wrote {}: stats.json, final.obj and {} frame meshes; mean step "
              "{:.2f} ms, {} tetrahedra cut in {} cuts",
              out.string(), frames / scene.output.mesh_every_n_frames,
              total_ms / std::max(frames, 1), cut_tets,
              sim.model().cut_count());
}

} // namespace vox::app
