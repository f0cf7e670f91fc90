#include "bench/harness/glide.hpp"

#include "core/atomic_file.hpp"
#include "core/log.hpp"
#include "core/sample_stats.hpp"
#include "io/scene_object.hpp"
#include "sim/device_run.hpp"
#include "sim/frame_loop.hpp"
#include "sim/method_factory.hpp"

#include <nlohmann/json.hpp>

#include <algorithm>
#include <cmath>
#include <fstream>
#include <sstream>

namespace vox::bench {
namespace {

constexpr double k_start_mm = 8.0, k_end_mm = 32.0, k_settle_s = 0.4;

/// The block, the ball and its script: down 1 mm over 0.2 s, still until k_settle_s, across
/// from x = 8 to 32 mm at `speed`, still for 0.2 s.
io::Scene glide_scene(io::SolverType method, double speed)
{
    const double glide_s = (k_end_mm - k_start_mm) / speed;
    nlohmann::json s = {
        {"object", {{"phantom", {{"shape", "beam"}, {"size_mm", {40, 20, 10}}, {"voxel_mm", 1.0}}}, {"levels", 1}}},
        {"materials", {{"default", {{"youngs_modulus_pa", 2e4}, {"poisson_ratio", 0.3}, {"density_kg_m3", 1000}}}}},
        {"solver", {{"type", io::solver_type_name(method)}, {"dt_s", 0.01}}},
        {"gravity_m_s2", {0, 0, -9.81}},
        {"constraints", {{{"type", "fixed"}, {"box_mm", {{-1, -1, -1}, {41, 21, 1}}}}}},
        {"tools", {{{"name", "ball"}, {"shape", "sphere"}, {"radius_mm", 3}}}},
        {"script",
         {{{"t_s", 0.0}, {"tool", "ball"}, {"position_mm", {k_start_mm, 10, 15}}},
          {{"t_s", 0.2}, {"tool", "ball"}, {"position_mm", {k_start_mm, 10, 12}}},
          {{"t_s", k_settle_s}, {"tool", "ball"}, {"position_mm", {k_start_mm, 10, 12}}},
          {{"t_s", k_settle_s + glide_s}, {"tool", "ball"}, {"position_mm", {k_end_mm, 10, 12}}},
          {{"t_s", k_settle_s + glide_s + 0.2}, {"tool", "ball"}, {"position_mm", {k_end_mm, 10, 12}}}}}};
    return io::parse_scene(s, std::filesystem::current_path(), "glide scene");
}

} // namespace

GlideFigures glide(io::SolverType method, double speed_mm_s)
{
    const io::Scene scene = glide_scene(method, speed_mm_s);
    auto opened = sim::open_method(scene, std::make_shared<const grid::LabelGrid>(io::load_scene_object(scene)));
    sim::ToolPolicy tools(scene);
    sim::DeviceRun device(scene, tools, sim::DeviceOptions{});
    sim::FrameLoop loop(scene, *opened.method, tools, &device);
    const double end_s = scene.script.back().t_s;
    while (loop.frames() * scene.solver.dt_s < end_s) loop.next();
    GlideFigures out;
    out.method = method;
    out.speed_mm_s = speed_mm_s;
    std::vector<double> changes;
    const std::vector<sim::ForceSample>& forces = device.forces();
    const double from = k_settle_s + 0.1, to = end_s - 0.2; // settled in, gliding
    for (std::size_t i = 1; i < forces.size(); ++i) {
        if (forces[i - 1].t_s < from || forces[i].t_s > to) continue;
        changes.push_back((forces[i].force_n - forces[i - 1].force_n).norm());
        out.mean_force_n += forces[i].force_n.norm();
    }
    if (changes.empty()) return out;
    out.ticks = changes.size();
    out.mean_force_n /= static_cast<double>(changes.size());
    out.largest_change_n = *std::max_element(changes.begin(), changes.end());
    out.p99_change_n = quantile(changes, 0.99);
    out.median_change_n = quantile(changes, 0.5);
    return out;
}

void run_glide_bench(const std::filesystem::path& dir)
{
    std::vector<GlideFigures> rows;
    for (const double speed : {20.0, 60.0})
        for (const io::SolverType method : {io::SolverType::dbg, io::SolverType::isxfem, io::SolverType::shape_matching}) {
            log::info("bench glide: {} at {:g} mm/s", io::solver_type_name(method), speed);
            rows.push_back(glide(method, speed));
        }
    std::ostringstream md;
    md << "# The force while a ball glides across a block (`voxsculpt bench glide`)\n\n"
       << "machine: " << machine_description() << "\n\n"
       << "A ball of 3 mm radius pressed 1 mm into a block (E = 20 kPa, level 1) and drawn 24 mm across it, "
          "through the device path at 1 kHz; the change of the force from one tick to the next while it glides.\n\n"
       << "| method | speed | ticks | mean force | largest change per tick | p99 | median |\n|---|---|---|---|---|---|---|\n";
    nlohmann::json j = nlohmann::json::array();
    char line[256];
    for (const GlideFigures& r : rows) {
        std::snprintf(line, sizeof line, "| %s | %g mm/s | %zu | %.4f N | %.5f N (%.1f %%) | %.5f N | %.5f N |\n",
                      std::string(io::solver_type_name(r.method)).c_str(), r.speed_mm_s, r.ticks, r.mean_force_n, r.largest_change_n,
                      100.0 * r.largest_change_n / std::max(r.mean_force_n, 1e-12), r.p99_change_n, r.median_change_n);
        md << line;
        j.push_back({{"method", io::solver_type_name(r.method)},
                     {"speed_mm_s", r.speed_mm_s},
                     {"ticks", r.ticks},
                     {"mean_force_n", r.mean_force_n},
                     {"largest_change_n", r.largest_change_n},
                     {"p99_change_n", r.p99_change_n},
                     {"median_change_n", r.median_change_n}});
    }
    std::filesystem::create_directories(dir);
    write_atomically(dir / "glide.md", [&](const std::filesystem::path& tmp) { std::ofstream(tmp) << md.str(); });
    write_atomically(dir / "glide.json", [&](const std::filesystem::path& tmp) { std::ofstream(tmp) << j.dump(1) << '\n'; });
    std::printf("%s", md.str().c_str());
}

} // namespace vox::bench
