// voxsculpt bench haptics: how steady the 1 kHz loop is while a simulation runs beside it. The
// loop follows a scripted device and computes a stand-in contact force (a spring against a plane:
// the contact module's continuous forces replace it with the haptics issue); the main thread
// steps the liver at level 4 (dynamic, 1,232 elements) for the same time. Prints period error and
// force-computation time (p50, p99, max).

#include "app/bench_haptics.hpp"
#include "app/scene_simulation.hpp"
#include "core/log.hpp"
#include "core/sample_stats.hpp"
#include "haptics/haptic_loop.hpp"
#include "haptics/virtual_device.hpp"
#include "io/scene_object.hpp"

#include <nlohmann/json.hpp>

#include <algorithm>
#include <chrono>
#include <cstdio>

namespace vox::app {
namespace {

struct Percentiles {
    double p50 = 0, p99 = 0, max = 0;
};

Percentiles percentiles(const std::vector<double>& v)
{
    return {quantile(v, 0.5), quantile(v, 0.99), quantile(v, 1.0)};
}

} // namespace

void run_haptics_bench(double seconds)
{
    const nlohmann::json document{
        {"object", {{"volume", VOX_DATA_DIR "/liver.inr.gz"}, {"select", {{"label", {255}}}}, {"levels", 4}}},
        {"materials", {{"default", {{"youngs_modulus_pa", 3e4}, {"poisson_ratio", 0.45}, {"density_kg_m3", 1060}}}}},
        {"solver", {{"dt_s", 0.01}, {"preconditioner", "jacobi"}}},
        {"gravity_m_s2", {0, 0, -9.81}},
        {"constraints", {{{"type", "fixed"}, {"box_mm", {{-1e4, -1e4, -1e4}, {1e4, 1e4, 60}}}}}}};
    const io::Scene scene = io::parse_scene(document, std::filesystem::current_path(), "bench haptics scene");
    const grid::LabelGrid labels = io::build_scene_object(scene);
    const grid::BranchedGrid g = build_scene_grid(scene, labels, 5);
    SceneSimulation sim(scene, g, 4);

    // The tool dips 10 mm into a plane and out again, once a second.
    std::vector<haptics::KeyFrame> frames;
    for (int k = 0; k <= static_cast<int>(seconds) + 1; ++k) {
        frames.push_back({static_cast<double>(k), {0, 0, 5}, Eigen::Quaterniond::Identity()});
        frames.push_back({k + 0.5, {0, 0, -10}, Eigen::Quaterniond::Identity()});
    }
    haptics::VirtualDevice device(frames);
    haptics::HapticLoop loop(
        device,
        [](const haptics::DeviceState& s, double& age) -> Eigen::Vector3d {
            age = 0.0;
            return s.position_mm.z() < 0 ? Eigen::Vector3d(0, 0, -0.3 * s.position_mm.z()) : Eigen::Vector3d::Zero();
        },
        haptics::SafetySettings{}, static_cast<std::size_t>(seconds * 1000) + 1000);

    log::info("bench haptics: 1 kHz loop for {} s beside the liver simulation (level 4)", seconds);
    loop.start();
    const auto start = std::chrono::steady_clock::now();
    int steps = 0;
    while (std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count() < seconds) {
        sim.solver().step();
        ++steps;
    }
    loop.stop();
    const Percentiles period = percentiles(loop.timings().period_error_ms);
    const Percentiles force = percentiles(loop.timings().force_us);
    std::printf("| ticks | simulation steps | real-time priority | period error p50 / p99 / max | force time p50 / p99 / max |\n"
                "|---|---|---|---|---|\n");
    std::printf("| %zu | %d | %s | %.4f / %.4f / %.3f ms | %.2f / %.2f / %.1f us |\n", loop.timings().period_error_ms.size(), steps,
                loop.timings().realtime_priority ? "yes" : "no (not permitted)", period.p50, period.p99, period.max, force.p50,
                force.p99, force.max);
}

} // namespace vox::app
