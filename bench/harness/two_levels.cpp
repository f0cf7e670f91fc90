// voxsculpt bench levels: what two levels in one model buy. Each case (a ball pressed into a beam
// held at both ends, a blade cutting into it, a probe pressed into the liver CT, the liver
// incision) runs the same script with the uniform fine level (the reference), the fine level
// around the tools on a coarse one (the region following the tools), for two fine levels, and the
// uniform levels between and coarse. Every column comes from the same code for every model:
// the tool's reaction force against the reference's (RMS over the frames of the difference, over
// the reference's RMS), the deformed surface within a distance of the tool's last position
// against the reference's, the faces a cut opened that the reference's did not (or the other way
// round), and the whole frame's wall time.

#include "bench/harness/two_levels.hpp"

#include "bench/harness/log_plot.hpp"
#include "bench/harness/surface_state.hpp"
#include "core/atomic_file.hpp"
#include "core/log.hpp"
#include "core/sample_stats.hpp"
#include "io/scene_object.hpp"
#include "sim/frame_loop.hpp"

#include <nlohmann/json.hpp>

#include <array>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <optional>
#include <set>
#include <sstream>

namespace vox::bench {
namespace {

/// One model of a case: one level, or two.
struct Model {
    int level = 0; ///< the level, or the coarse one of two
    std::optional<io::MixedLevelsSpec> two;
    [[nodiscard]] std::string name() const
    {
        return two ? std::to_string(two->fine) + "/" + std::to_string(two->coarse) : std::to_string(level);
    }
};

Model uniform(int level) { return {level, std::nullopt}; }
Model two_levels(int fine, int coarse, double radius_mm) { return {coarse, io::MixedLevelsSpec{fine, coarse, radius_mm}}; }

struct Case {
    std::string name, what;
    io::Scene scene;
    std::shared_ptr<const grid::LabelGrid> labels;
    int frames = 0;
    double near_mm = 0.0;      ///< the surface within this of the tool's last position is compared
    std::vector<Model> models; ///< the reference, the uniform fine level, first
};

struct Run {
    Model model;
    std::string linear_solver;
    std::size_t dofs_max = 0, region_moves = 0;
    std::map<int, std::size_t> elements; ///< per level, at the end
    std::vector<Eigen::Vector3d> force_n; ///< per frame, on the first tool
    Eigen::Vector3d tool_mm = Eigen::Vector3d::Zero();
    std::vector<double> frame_ms;
    int converged = 0;
    std::set<std::array<int, 4>> faces; ///< opened by the cuts: voxel, axis
    SurfaceState surface;
};

Run run_model(const Case& c, const Model& m)
{
    io::Scene scene = c.scene;
    scene.object.levels = m.level;
    scene.object.mixed_levels = m.two;
    log::info("bench levels: {}, level {}", c.name, m.name());
    sim::DbgMethod method(scene, c.labels, m.level, m.two ? m.level : std::min(6, m.level + 2));
    sim::ToolPolicy tools(scene);
    sim::FrameLoop loop(scene, method, tools);
    Run r;
    r.model = m;
    for (int f = 0; f < c.frames; ++f) {
        const sim::FrameStats s = loop.next();
        r.frame_ms.push_back(s.frame_ms);
        r.force_n.push_back(s.tools.tools[0].force_n);
        if (s.tools.tools[0].placed) r.tool_mm = s.tools.tools[0].position_mm;
        r.dofs_max = std::max(r.dofs_max, method.dof_count());
        r.converged += s.step.converged ? 1 : 0;
    }
    r.linear_solver = method.linear_solver();
    r.elements = method.elements_per_level();
    nlohmann::json summary;
    method.add_summary_figures(summary);
    r.region_moves = summary.value("fine_region_moves", std::size_t{0});
    for (const auto& cut : method.cuts_since(0))
        for (const auto& f : cut["faces"]) r.faces.insert(f.get<std::array<int, 4>>());
    r.surface = surface_state(method);
    return r;
}

/// RMS over the frames of the force's difference from the reference's, over the reference's RMS.
double force_error(const Run& r, const Run& reference)
{
    double diff = 0.0, norm = 0.0;
    for (std::size_t f = 0; f < reference.force_n.size() && f < r.force_n.size(); ++f) {
        diff += (r.force_n[f] - reference.force_n[f]).squaredNorm();
        norm += reference.force_n[f].squaredNorm();
    }
    return norm > 0.0 ? std::sqrt(diff / norm) : 0.0;
}

/// The same of the surface displacements within `near_mm` of the reference's tool, where the
/// reference's surface is now.
double surface_error(const Run& r, const Run& reference, double near_mm)
{
    double diff = 0.0, norm = 0.0;
    for (const auto& [key, u] : reference.surface.displacement_mm) {
        if ((reference.surface.rest_mm.at(key) + u - reference.tool_mm).norm() > near_mm) continue;
        const auto it = r.surface.displacement_mm.find(key);
        if (it == r.surface.displacement_mm.end()) continue;
        diff += (it->second - u).squaredNorm();
        norm += u.squaredNorm();
    }
    return norm > 0.0 ? std::sqrt(diff / norm) : 0.0;
}

double peak_force(const Run& r)
{
    double peak = 0.0;
    for (const Eigen::Vector3d& f : r.force_n) peak = std::max(peak, f.norm());
    return peak;
}

std::size_t faces_apart(const Run& r, const Run& reference)
{
    std::size_t n = 0;
    for (const auto& f : r.faces) n += reference.faces.count(f) ? 0 : 1;
    for (const auto& f : reference.faces) n += r.faces.count(f) ? 0 : 1;
    return n;
}

std::string elements_text(const std::map<int, std::size_t>& elements)
{
    std::string out;
    for (const auto& [level, count] : elements) out += (out.empty() ? "" : ", ") + std::to_string(count) + " at " + std::to_string(level);
    return out;
}

/// A 120 x 24 x 24 mm beam of soft material (1 mm voxels) without gravity, held at both ends (a
/// bridge, which bends as a whole) or along its underside (lying on a table); levels 1 (8,640
/// elements) to 3 (cells 8 mm wide).
enum class Held { ends, underside };
nlohmann::json beam(Held held, const nlohmann::json& tools, const nlohmann::json& script)
{
    const nlohmann::json constraints =
        held == Held::ends ? nlohmann::json{{{"type", "fixed"}, {"box_mm", {{-1, -1, -1}, {1, 25, 25}}}}, {{"type", "fixed"}, {"box_mm", {{118, -1, -1}, {121, 25, 25}}}}}
                           : nlohmann::json{{{"type", "fixed"}, {"box_mm", {{-1, -1, -1}, {121, 25, 0}}}}};
    return {{"object", {{"phantom", {{"shape", "block"}, {"size_mm", {120, 24, 24}}, {"voxel_mm", 1}}}, {"levels", 1}}},
            {"materials", {{"default", {{"youngs_modulus_pa", 3e4}, {"poisson_ratio", 0.45}, {"density_kg_m3", 1000}}}}},
            {"solver", {{"type", "dbg"}, {"dt_s", 0.01}, {"rayleigh_mass_per_s", 10.0}, {"cg_max_iterations", 400}}},
            {"gravity_m_s2", {0, 0, 0}},
            {"constraints", constraints},
            {"tools", tools},
            {"script", script}};
}

std::vector<Case> cases(bool liver)
{
    std::vector<Case> out;
    const auto add = [&](std::string name, std::string what, const io::Scene& scene, int frames, double near_mm, std::vector<Model> models) {
        auto labels = std::make_shared<const grid::LabelGrid>(io::load_scene_object(scene));
        out.push_back({std::move(name), std::move(what), scene, std::move(labels), frames, near_mm, std::move(models)});
    };
    const std::vector<Model> beam_models{uniform(1), two_levels(1, 3, 5), two_levels(2, 3, 5), uniform(2), uniform(3)};
    add("beam press", "the beam held at both ends; a 5 mm ball pressed 3 mm into the middle of its top over 0.5 s, then held 0.3 s",
        io::parse_scene(beam(Held::ends, {{{"name", "ball"}, {"shape", "sphere"}, {"radius_mm", 5}, {"action", "push"}}},
                             {{{"t_s", 0.0}, {"tool", "ball"}, {"position_mm", {59.5, 11.5, 29}}},
                              {{"t_s", 0.5}, {"tool", "ball"}, {"position_mm", {59.5, 11.5, 26}}},
                              {{"t_s", 0.8}, {"tool", "ball"}, {"position_mm", {59.5, 11.5, 26}}}}),
                        std::filesystem::current_path(), "bench beam press"),
        80, 15.0, beam_models);
    const nlohmann::json across{0.7071068, 0, 0, 0.7071068}; // the blade's edge along y
    add("beam cut", "the beam held along its underside; a blade across it at x = 40 mm, lowered 20 mm (its edge 15 mm into the beam) over "
                    "0.5 s, then held 0.2 s",
        io::parse_scene(beam(Held::underside, {{{"name", "blade"}, {"shape", "blade"}, {"size_mm", {40, 0.5, 10}}, {"cut_mode", "separate"}, {"cut_pressure_pa", 3e3}}},
                             {{{"t_s", 0.0}, {"tool", "blade"}, {"position_mm", {40, 11.5, 34}}, {"orientation_wxyz", across}},
                              {{"t_s", 0.5}, {"tool", "blade"}, {"position_mm", {40, 11.5, 14}}, {"orientation_wxyz", across}},
                              {{"t_s", 0.7}, {"tool", "blade"}, {"position_mm", {40, 11.5, 14}}, {"orientation_wxyz", across}}}),
                        std::filesystem::current_path(), "bench beam cut"),
        70, 15.0, beam_models);
    if (!liver) return out;
    // The liver CT (label 255), its back held as in the incision.
        const nlohmann::json press{
        {"object", {{"volume", VOX_DATA_DIR "/liver.inr.gz"}, {"select", {{"label", {255}}}}, {"levels", 4}}},
        {"materials", {{"default", {{"youngs_modulus_pa", 3e4}, {"poisson_ratio", 0.45}, {"density_kg_m3", 1060}}}}},
        {"solver", {{"type", "dbg"}, {"dt_s", 0.01}, {"cg_tolerance", 1e-6}, {"cg_max_iterations", 400}, {"preconditioner", "jacobi"}}},
        {"gravity_m_s2", {0, 0, 0}},
        {"constraints", {{{"type", "fixed"}, {"box_mm", {{0, 100, 0}, {270, 220, 220}}}}}},
        {"tools", {{{"name", "probe"}, {"shape", "sphere"}, {"radius_mm", 5}}}},
        {"script",
         {{{"t_s", 0.0}, {"tool", "probe"}, {"position_mm", {150, 0, 120}}},
          {{"t_s", 0.6}, {"tool", "probe"}, {"position_mm", {150, 40, 120}}},
          {{"t_s", 1.0}, {"tool", "probe"}, {"position_mm", {150, 40, 120}}}}}};
    const std::vector<Model> press_models{uniform(2), two_levels(2, 4, 15), two_levels(3, 4, 15), uniform(3), uniform(4)};
    add("liver press", "a 5 mm probe pushed 40 mm into the liver's front over 0.6 s, then held 0.4 s (its back held, no gravity)",
        io::parse_scene(press, std::filesystem::current_path(), "bench liver press"), 100, 25.0, press_models);
    const io::Scene incision = io::load_scene(VOX_DATA_DIR "/scenes/liver_incision.json");
    const std::vector<Model> cut_models{uniform(2), two_levels(2, 4, 10), two_levels(3, 4, 10), uniform(3), uniform(4)};
    add("liver incision", "data/scenes/liver_incision.json: a scalpel enters 8 mm deep, draws 50 mm and withdraws (gravity on)", incision, 150,
        25.0, cut_models);
    return out;
}

} // namespace

void run_two_levels_bench(const std::filesystem::path& out, bool liver)
{
    std::ostringstream md;
    md << "One run of each model, whole frames (tools, cuts, region moves, step) by wall clock; machine: " << machine_description()
       << ". Errors against the uniform fine level (the first row): the first tool's force, RMS over all frames of the difference over "
          "the reference's RMS; the deformed surface within the stated distance of the tool's last position, the same. Two levels "
          "solve with Jacobi; the uniform levels with the scene's preconditioner.\n";
    nlohmann::json data = nlohmann::json::object();
    std::vector<PlotSeries> force_plot, surface_plot;
    for (const Case& c : cases(liver)) {
        std::vector<Run> runs;
        for (const Model& m : c.models) runs.push_back(run_model(c, m));
        const Run& reference = runs.front();
        md << "\n## " << c.name << "\n\n" << c.what << "; " << c.frames << " frames of " << c.scene.solver.dt_s << " s; surface compared within "
           << c.near_mm << " mm of the tool.\n\n"
           << "| levels | DOFs (most) | elements at the end | linear solver | force error | peak force (N) | surface error near the tool | "
              "faces opened (apart from the reference's) | frame median (ms) | frame p95 (ms) | time vs fine | region moves | converged frames |\n"
           << "|---|---|---|---|---|---|---|---|---|---|---|---|---|\n";
        nlohmann::json rows = nlohmann::json::array();
        force_plot.push_back({c.name, {}, false}); // the rows are models, not a sequence
        surface_plot.push_back({c.name, {}, false});
        for (const Run& r : runs) {
            const double fe = force_error(r, reference), se = surface_error(r, reference, c.near_mm);
            const double median = quantile(r.frame_ms, 0.5), p95 = quantile(r.frame_ms, 0.95);
            const double ratio = median / quantile(reference.frame_ms, 0.5);
            char line[512];
            std::snprintf(line, sizeof line, "| %s | %zu | %s | %s | %.1f %% | %.3f | %.1f %% | %zu (%zu) | %.1f | %.1f | %.3f | %zu | %d of %d |\n",
                          r.model.name().c_str(), r.dofs_max, elements_text(r.elements).c_str(), r.linear_solver.c_str(), 100 * fe,
                          peak_force(r), 100 * se, r.faces.size(), faces_apart(r, reference), median, p95, ratio, r.region_moves, r.converged,
                          c.frames);
            md << line;
            rows.push_back({{"levels", r.model.name()}, {"dofs_max", r.dofs_max}, {"linear_solver", r.linear_solver},
                            {"force_error", fe}, {"peak_force_n", peak_force(r)}, {"surface_error_near_tool", se},
                            {"faces_opened", r.faces.size()}, {"faces_apart", faces_apart(r, reference)}, {"frame_ms_median", median},
                            {"frame_ms_p95", p95}, {"time_vs_fine", ratio}, {"region_moves", r.region_moves}, {"converged_frames", r.converged}});
            force_plot.back().points.push_back({median, 100 * fe, r.model.name()});
            surface_plot.back().points.push_back({median, 100 * se, r.model.name()});
        }
        data[c.name] = rows;
    }
    md << "\n![force error against frame time](levels_force.svg)\n\n![surface error near the tool against frame time](levels_surface.svg)\n";
    std::filesystem::create_directories(out);
    write_atomically(out / "levels.md", [&](const std::filesystem::path& tmp) { std::ofstream(tmp) << md.str(); });
    write_atomically(out / "levels.json", [&](const std::filesystem::path& tmp) { std::ofstream(tmp) << data.dump(1) << '\n'; });
    write_atomically(out / "levels_force.svg", [&](const std::filesystem::path& tmp) {
        std::ofstream(tmp) << log_log_plot(force_plot, "frame time, median, ms (log)", "force error against the uniform fine level, % (log)");
    });
    write_atomically(out / "levels_surface.svg", [&](const std::filesystem::path& tmp) {
        std::ofstream(tmp) << log_log_plot(surface_plot, "frame time, median, ms (log)", "surface error near the tool, % (log)");
    });
    std::printf("%s\nwrote %s\n", md.str().c_str(), (out / "levels.md").c_str());
}

} // namespace vox::bench
