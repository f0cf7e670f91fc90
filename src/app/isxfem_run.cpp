#include "app/isxfem_run.hpp"

#include "app/isxfem_simulation.hpp"
#include "app/scene_simulation.hpp"
#include "contact/tool_shape.hpp"
#include "core/atomic_file.hpp"
#include "core/error.hpp"
#include "core/log.hpp"
#include "core/progress.hpp"
#include "io/mesh_writer.hpp"
#include "io/scene_object.hpp"
#include "io/tool_script.hpp"

#include <nlohmann/json.hpp>

#include <chrono>
#include <cmath>
#include <fstream>

namespace vox::app {
namespace {

/// A blade's cut while its mid-plane stays put: the union of the regions its profile swept in that
/// plane, frame by frame, so a tetrahedron the blade crosses whole only over several frames is cut
/// once it has been.
class BladeStroke {
public:
    explicit BladeStroke(const io::ToolSpec& tool)
        : m_profile((tool.shape == io::ToolShape::scalpel ? contact::ToolShape::scalpel(tool.size_mm) : contact::ToolShape::box(tool.size_mm))
                        .profile())
    {
    }

    /// The blade moved from `from` to `to` over a frame; cuts where it has passed. Starts a new cut
    /// when its plane moved or turned.
    isxfem::CutReport advance(IsxfemSimulation& sim, const io::ToolPose& from, const io::ToolPose& to)
    {
        const Eigen::Matrix3d r = to.orientation.toRotationMatrix();
        const Eigen::Vector3d normal = r.col(1);
        const bool same_plane = m_cut >= 0 && (normal - m_rotation.col(1)).norm() < 1e-9 &&
                                std::abs((to.position_mm - m_origin_mm).dot(normal)) < 1e-6;
        if (!same_plane) {
            m_cut = -1;
            m_rotation = r;
            m_origin_mm = to.position_mm;
            m_segments.clear();
        }
        // The motion in the plane, in the stroke's x-z coordinates (motion across it is ignored).
        auto in_plane = [&](const Eigen::Vector3d& p_mm) {
            const Eigen::Vector3d local = m_rotation.transpose() * (p_mm - m_origin_mm);
            return Eigen::Vector2d(local.x(), local.z());
        };
        m_segments.push_back({in_plane(from.placed ? from.position_mm : to.position_mm), in_plane(to.position_mm)});
        const auto inside = [this, &in_plane](const Eigen::Vector3d& p_m) { return covered(in_plane(p_m * 1e3)); };
        const isxfem::CutReport report = sim.cut(m_origin_mm * 1e-3, m_rotation.col(1), inside, m_cut);
        if (report.cut >= 0) m_cut = report.cut;
        return report;
    }

private:
    /// Whether q lies in the profile moved along any segment: some t in [0, 1] with q - a - t (b - a)
    /// inside every edge's half-plane of the convex, counter-clockwise profile.
    [[nodiscard]] bool covered(const Eigen::Vector2d& q) const
    {
        for (const auto& [a, b] : m_segments) {
            double lo = 0.0, hi = 1.0;
            const Eigen::Vector2d d = b - a, p = q - a;
            for (std::size_t k = 0; k < m_profile.size() && lo <= hi; ++k) {
                const Eigen::Vector2d& e0 = m_profile[k];
                const Eigen::Vector2d& e1 = m_profile[(k + 1) % m_profile.size()];
                const Eigen::Vector2d outward(e1.y() - e0.y(), e0.x() - e1.x()); // right of a counter-clockwise edge
                // outward . (p - t d - e0) <= 0  <=>  t (outward . d) >= outward . (p - e0)
                const double c = outward.dot(p - e0), s = outward.dot(d);
                if (std::abs(s) < 1e-300) {
                    if (c > 0.0) hi = -1.0;
                } else if (s > 0.0) {
                    lo = std::max(lo, c / s);
                } else {
                    hi = std::min(hi, c / s);
                }
            }
            if (lo <= hi) return true;
        }
        return false;
    }

    std::vector<Eigen::Vector2d> m_profile; ///< mm, tool x-z
    int m_cut = -1;
    Eigen::Matrix3d m_rotation = Eigen::Matrix3d::Identity();
    Eigen::Vector3d m_origin_mm = Eigen::Vector3d::Zero();
    std::vector<std::pair<Eigen::Vector2d, Eigen::Vector2d>> m_segments;
};

void write_surface(const std::filesystem::path& path, const IsxfemSimulation& sim)
{
    const surface::SurfaceMesh m = sim.surface_mesh();
    io::write_mesh(path.string(), m.positions, m.triangles, m.labels);
}

} // namespace

void run_isxfem(const io::Scene& scene, const std::string& scene_path, std::optional<int> frame_count, const std::filesystem::path& out)
{
    for (std::size_t k = 0; k < scene.tools.size(); ++k) {
        const io::ToolSpec& t = scene.tools[k];
        if (t.action != io::ToolAction::cut || (t.shape != io::ToolShape::blade && t.shape != io::ToolShape::scalpel))
            throw scene.error("tools[" + std::to_string(k) + "]",
                              "\"" + t.name + "\": \"isxfem\" scenes cut with blades and scalpels only so far; pushing and wetting tools need \"type\": \"dbg\"");
        if (t.two_phase) throw scene.error("tools[" + std::to_string(k) + "].two_phase", "\"isxfem\" has no two-phase cutting yet");
    }
    if (scene.object.auto_levels) throw scene.error("object.levels", "\"isxfem\" needs a fixed level (0 to 6), not \"auto\"");
    const grid::LabelGrid labels = io::load_scene_object(scene);
    const int level = scene.object.levels;
    const grid::BranchedGrid g = build_scene_grid(scene, labels, std::max(level, 1));
    IsxfemSimulation sim(scene, g, level);
    std::vector<BladeStroke> strokes;
    for (const io::ToolSpec& t : scene.tools) strokes.emplace_back(t);

    const double dt = scene.solver.dt_s;
    const double duration = scene.script.empty() ? 0.0 : scene.script.back().t_s;
    const int frames = frame_count.value_or(duration > 0 ? static_cast<int>(std::ceil(duration / dt)) : 100);
    std::filesystem::create_directories(out);
    log::info("{}: isxfem (k = {}), level {}, {} tetrahedra, {} degrees of freedom, {} frames of {} s", scene_path, scene.solver.isxfem_k,
              level, sim.tet_count(), sim.solver().dof_count(), frames, dt);
    nlohmann::json stats{{"scene", scene_path}, {"solver", "isxfem"}, {"k", scene.solver.isxfem_k}, {"level", level},
                         {"tetrahedra", sim.tet_count()}, {"dofs", sim.solver().dof_count()}, {"dt_s", dt},
                         {"linear_solver", std::string("CG, ") + sim.solver().preconditioner_name() + " preconditioner"}, {"frames", nlohmann::json::array()}};
    double total_ms = 0.0, max_ms = 0.0, cut_total_ms = 0.0;
    int converged = 0;
    std::size_t cut_tets = 0, partial = 0;
    isxfem::XfemStepStats last;
    Progress progress("simulating", static_cast<std::uint64_t>(frames));
    const auto& rest = sim.model().mesh().nodes;
    for (int f = 1; f <= frames; ++f) {
        const auto cut_start = std::chrono::steady_clock::now();
        isxfem::CutReport frame_cut;
        for (std::size_t k = 0; k < scene.tools.size(); ++k) {
            const io::ToolPose from = io::tool_pose(scene, k, (f - 1) * dt), to = io::tool_pose(scene, k, f * dt);
            if (!to.placed) continue;
            const isxfem::CutReport r = strokes[k].advance(sim, from, to);
            frame_cut.cut_tets += r.cut_tets;
            frame_cut.new_blocks += r.new_blocks;
            frame_cut.partial_tets += r.partial_tets;
            frame_cut.already_cut += r.already_cut;
        }
        const double cut_ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - cut_start).count();
        cut_total_ms += cut_ms;
        cut_tets += frame_cut.cut_tets;
        partial = frame_cut.partial_tets;
        last = sim.solver().step();
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
                                   {"dofs", sim.solver().dof_count()}});
        if (f % scene.output.mesh_every_n_frames == 0) {
            char name[32];
            std::snprintf(name, sizeof name, "frame_%05d.obj", f);
            write_surface(out / name, sim);
        }
        progress.update(static_cast<std::uint64_t>(f));
    }
    progress.finish();
    stats["summary"] = {{"frames", frames},
                        {"total_step_ms", total_ms},
                        {"mean_step_ms", frames ? total_ms / frames : 0.0},
                        {"max_step_ms", max_ms},
                        {"converged_frames", converged},
                        {"cut_tets", cut_tets},
                        {"cuts", sim.model().cut_count()},
                        {"partly_crossed_tets_last_frame", partial},
                        {"total_cut_ms", cut_total_ms},
                        {"final_dofs", sim.solver().dof_count()},
                        {"final_kinetic_energy_j", last.kinetic_energy_j}};
    write_surface(out / "final.obj", sim);
    write_atomically(out / "stats.json", [&](const std::filesystem::path& tmp) { std::ofstream(tmp) << stats.dump(1) << '\n'; });
    log::info("wrote {}: stats.json, final.obj and {} frame meshes; mean step {:.2f} ms, {} tetrahedra cut in {} cuts", out.string(),
              frames / scene.output.mesh_every_n_frames, total_ms / std::max(frames, 1), cut_tets, sim.model().cut_count());
}

} // namespace vox::app
