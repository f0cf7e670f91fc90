// voxsculpt bench tradeoff: the speed/accuracy trade of the coarsening level, measured.
// A cantilever beam sagging under gravity (quasi-static) against Euler-Bernoulli and against its
// level-0 solution, and the liver against its level-1 solution. Errors compare the deformed
// surface, which follows the voxels and so is the same at every level; writes a Markdown table
// and an SVG plot of error against solve time.

#include "bench/harness/tradeoff.hpp"

#include "bench/harness/log_plot.hpp"
#include "bench/harness/surface_state.hpp"

#include "core/atomic_file.hpp"
#include "core/log.hpp"
#include "io/scene_object.hpp"
#include "sim/dbg_method.hpp"
#include "sim/frame_loop.hpp"

#include <nlohmann/json.hpp>

#include <cmath>
#include <cstdio>
#include <fstream>
#include <map>
#include <sstream>

namespace vox::bench {

using sim::DbgSimulation;

namespace {

constexpr int k_liver_reference = 1;

/// Quasi-static equilibrium under gravity at one level: surface displacements and cost.
struct Solution {
    int level = 0;
    SurfaceState surface;
    std::size_t elements = 0, dofs = 0;
    double solve_ms = 0.0;
    int cg_iterations = 0;
};

/// A scene document for a quasi-static solve of `object` under gravity -z, held in `held_box_mm`.
nlohmann::json static_scene(nlohmann::json object, double youngs_modulus_pa, double poisson_ratio, double density,
                            const nlohmann::json& held_box_mm, int level)
{
    object["levels"] = level;
    return {{"object", object},
            {"materials", {{"default", {{"youngs_modulus_pa", youngs_modulus_pa}, {"poisson_ratio", poisson_ratio},
                                        {"density_kg_m3", density}}}}},
            {"solver", {{"mode", "static"}, {"cg_tolerance", 1e-8}, {"cg_max_iterations", 5000}, {"newton_max_iterations", 30},
                        {"preconditioner", "auto"}}},
            {"gravity_m_s2", {0, 0, -9.81}},
            {"constraints", {{{"type", "fixed"}, {"box_mm", held_box_mm}}}}};
}

/// Quasi-static equilibrium of a scene at its level: surface displacements and cost.
Solution solve_static(const nlohmann::json& document)
{
    const io::Scene scene = io::parse_scene(document, std::filesystem::current_path(), "bench scene");
    auto labels = std::make_shared<const grid::LabelGrid>(io::build_scene_object(scene));
    const int level = scene.object.levels;
    // One frame of the frame loop every command uses: a static scene's frame is its equilibrium.
    sim::DbgMethod method(scene, labels, level, std::min(6, std::max(level, 1) + 3));
    sim::ToolPolicy tools(scene);
    const sim::StepFigures s = sim::FrameLoop(scene, method, tools).next().step;
    const DbgSimulation& sim = method.simulation();

    Solution out;
    out.level = level;
    out.elements = sim.model().elements().size();
    out.dofs = sim.solver().dof_count();
    out.solve_ms = s.step_ms;
    out.cg_iterations = s.cg_iterations;
    out.surface = surface_state(method);
    return out;
}

/// RMS of the displacement difference over the reference's RMS displacement.
double relative_error(const Solution& s, const Solution& reference)
{
    double diff = 0.0, norm = 0.0;
    for (const auto& [key, u] : reference.surface.displacement_mm) {
        const auto it = s.surface.displacement_mm.find(key);
        if (it == s.surface.displacement_mm.end()) continue;
        diff += (it->second - u).squaredNorm();
        norm += u.squaredNorm();
    }
    return std::sqrt(diff / norm);
}

/// Mean z displacement of the surface vertices on the beam's free end (x >= end_x), mm.
double tip_deflection(const Solution& s, double end_x)
{
    double sum = 0.0;
    int n = 0;
    for (const auto& [key, p] : s.surface.rest_mm)
        if (p.x() >= end_x) {
            sum += s.surface.displacement_mm.at(key).z();
            ++n;
        }
    return n ? sum / n : 0.0;
}

} // namespace

void run_tradeoff(const std::filesystem::path& out, bool liver)
{
    std::ostringstream md;
    // The beam: 200 x 10 x 10 mm of 1 mm voxels, clamped at x = -0.5 mm, E = 1e8 Pa, nu = 0.3,
    // rho = 1000 kg/m^3: Euler-Bernoulli tip deflection q L^4 / (8 E I) = 2.354 mm (1.2 % of L).
    const double q = 1000.0 * 9.81 * 1e-4, length = 0.2, inertia = 1e-8 / 12.0;
    const double euler_bernoulli_mm = q * std::pow(length, 4) / (8 * 1e8 * inertia) * 1e3;
    std::vector<Solution> beam_rows;
    for (int level = 0; level <= 4; ++level) {
        log::info("bench tradeoff: beam, level {}", level);
        beam_rows.push_back(solve_static(static_scene({{"phantom", {{"shape", "beam"}}}}, 1e8, 0.3, 1000.0,
                                                      {{-1e3, -1e3, -1e3}, {0, 1e3, 1e3}}, level)));
    }
    std::vector<double> beam_errors;
    md << "Cantilever beam 200 x 10 x 10 mm (1 mm voxels), E = 1e8 Pa, nu = 0.3, sagging under gravity, "
          "quasi-static (Newton + preconditioned CG to 1e-8: warped Cholesky up to 20 k DOFs, multigrid above). Euler-Bernoulli tip deflection: "
       << euler_bernoulli_mm << " mm.\n\n"
       << "| level | elements | DOFs | tip deflection (mm) | error vs Euler-Bernoulli | error vs level 0 (surface) | "
          "solve time (ms) | CG iterations |\n|---|---|---|---|---|---|---|---|\n";
    for (const Solution& s : beam_rows) {
        const double tip = -tip_deflection(s, 199.4);
        const double error = s.level == 0 ? 0.0 : relative_error(s, beam_rows.front());
        beam_errors.push_back(error);
        char line[256];
        std::snprintf(line, sizeof line, "| %d | %zu | %zu | %.4f | %+.1f %% | %.2f %% | %.0f | %d |\n", s.level, s.elements,
                      s.dofs, tip, 100 * (tip / euler_bernoulli_mm - 1), 100 * error, s.solve_ms, s.cg_iterations);
        md << line;
    }
    std::vector<std::pair<std::string, std::vector<Solution>>> series{{"beam vs level 0", beam_rows}};
    std::vector<std::vector<double>> errors{beam_errors};

    if (liver) {
        const nlohmann::json liver_object{{"volume", VOX_DATA_DIR "/liver.inr.gz"}, {"select", {{"label", {255}}}}};
        std::vector<Solution> liver_rows;
        for (int level = k_liver_reference; level <= 5; ++level) {
            log::info("bench tradeoff: liver, level {}", level);
            liver_rows.push_back(solve_static(static_scene(liver_object, 1e8, 0.45, 1060.0, {{-1e4, -1e4, -1e4}, {1e4, 1e4, 60}}, level)));
        }
        std::vector<double> liver_errors;
        md << "\nLiver (label 255, 3.16 M voxels), E = 1e8 Pa, nu = 0.45, held below z = 60 mm, sagging under "
              "gravity, quasi-static; reference: level "
           << k_liver_reference << ".\n\n"
           << "| level | elements | DOFs | RMS surface displacement (mm) | error vs reference (surface) | solve time (ms) | "
              "CG iterations |\n|---|---|---|---|---|---|---|\n";
        for (const Solution& s : liver_rows) {
            double rms = 0.0;
            for (const auto& [key, u] : s.surface.displacement_mm) rms += u.squaredNorm();
            rms = std::sqrt(rms / static_cast<double>(s.surface.displacement_mm.size()));
            const double error = s.level == k_liver_reference ? 0.0 : relative_error(s, liver_rows.front());
            liver_errors.push_back(error);
            char line[256];
            std::snprintf(line, sizeof line, "| %d | %zu | %zu | %.4f | %.2f %% | %.0f | %d |\n", s.level, s.elements, s.dofs,
                          rms, 100 * error, s.solve_ms, s.cg_iterations);
            md << line;
        }
        series.emplace_back("liver vs level " + std::to_string(k_liver_reference), liver_rows);
        errors.push_back(liver_errors);
    }
    md << "\n![error against solve time](tradeoff.svg)\n";
    // The same rows as data.
    nlohmann::json data = nlohmann::json::object();
    for (std::size_t k = 0; k < series.size(); ++k) {
        nlohmann::json rows = nlohmann::json::array();
        for (std::size_t i = 0; i < series[k].second.size(); ++i) {
            const Solution& s = series[k].second[i];
            rows.push_back({{"level", s.level}, {"elements", s.elements}, {"dofs", s.dofs}, {"solve_ms", s.solve_ms},
                            {"cg_iterations", s.cg_iterations}, {"surface_error", errors[k][i]}});
        }
        data[series[k].first] = rows;
    }
    data["beam_euler_bernoulli_tip_mm"] = euler_bernoulli_mm;
    std::filesystem::create_directories(out);
    write_atomically(out / "tradeoff.md", [&](const std::filesystem::path& tmp) { std::ofstream(tmp) << md.str(); });
    write_atomically(out / "tradeoff.json", [&](const std::filesystem::path& tmp) { std::ofstream(tmp) << data.dump(1) << '\n'; });
    std::vector<PlotSeries> plot;
    for (std::size_t k = 0; k < series.size(); ++k) {
        plot.push_back({series[k].first, {}});
        for (std::size_t i = 0; i < series[k].second.size(); ++i)
            plot.back().points.push_back({series[k].second[i].solve_ms, 100 * errors[k][i], std::string("L").append(std::to_string(series[k].second[i].level))});
    }
    write_atomically(out / "tradeoff.svg", [&](const std::filesystem::path& tmp) {
        std::ofstream(tmp) << log_log_plot(plot, "quasi-static solve time, ms (log)", "relative error of the deformed surface, % (log)");
    });
    std::printf("%s\nwrote %s and %s\n", md.str().c_str(), (out / "tradeoff.md").c_str(), (out / "tradeoff.svg").c_str());
}


} // namespace vox::bench
