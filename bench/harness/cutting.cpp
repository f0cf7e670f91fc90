// voxsculpt bench cutting: how long a cutting frame takes on the liver at level 4 during the 5 cm
// incision of data/scenes/liver_incision.json. A cutting frame is every frame in which the scalpel
// cut: collision (contact of the tool with the surface) + propagation (the faces its section
// crossed) + grid update + local remesh, the paper's phases; the model rebuild that follows a cut
// and the solver step are reported beside it. Each run replays the whole scene from scratch.

#include "bench/harness/cutting.hpp"
#include "sim/frame_loop.hpp"
#include "sim/method_factory.hpp"
#include "core/log.hpp"
#include "core/sample_stats.hpp"
#include "io/scene_object.hpp"

#include <cmath>
#include <cstdio>

namespace vox::bench {

void run_cutting_bench(int runs)
{
    const io::Scene scene = io::load_scene(VOX_DATA_DIR "/scenes/liver_incision.json");
    const auto labels = std::make_shared<const grid::LabelGrid>(io::load_scene_object(scene));
    const int frames = static_cast<int>(std::ceil(scene.script.back().t_s / scene.solver.dt_s));
    std::printf("machine: %s; liver incision (data/scenes/liver_incision.json), level %d, %d frames a run\n\n",
                machine_description().c_str(), scene.object.levels, frames);
    std::printf("| run | cutting frames | cutting frame p50 / p95 / max | collision | propagation | grid update | remesh | "
                "model rebuild (median) | solver step (median) | faces opened |\n|---|---|---|---|---|---|---|---|---|---|\n");
    std::vector<double> p95s;
    for (int run = 1; run <= runs; ++run) {
        const std::unique_ptr<sim::Method> method = sim::open_method(scene, labels).method;
        sim::ToolPolicy tools(scene);
        sim::FrameLoop loop(scene, *method, tools);
        std::vector<double> cutting, collision, propagation, update, remesh, rebuild, step;
        std::size_t faces = 0;
        for (int f = 1; f <= frames; ++f) {
            const sim::FrameStats s = loop.next();
            step.push_back(s.step.step_ms);
            const sim::CutFigures& c = s.tools.cut;
            if (!c.changed()) continue;
            cutting.push_back(s.tools.cutting_ms());
            collision.push_back(s.tools.collision_ms);
            propagation.push_back(s.tools.propagation_ms);
            update.push_back(c.grid_update_ms);
            remesh.push_back(c.remesh_ms);
            rebuild.push_back(c.fem_update_ms);
            faces += c.separated_faces;
        }
        p95s.push_back(quantile(cutting, 0.95));
        std::printf("| %d | %zu | %.2f / %.2f / %.2f ms | %.2f ms | %.2f ms | %.2f ms | %.2f ms | %.1f ms | %.1f ms | %zu |\n", run,
                    cutting.size(), quantile(cutting, 0.5), quantile(cutting, 0.95), quantile(cutting, 1.0), quantile(collision, 0.5),
                    quantile(propagation, 0.5), quantile(update, 0.5), quantile(remesh, 0.5), quantile(rebuild, 0.5),
                    quantile(step, 0.5), faces);
        std::fflush(stdout);
    }
    std::printf("\np95 of the cutting frame over %d runs: median %.2f ms, range %.2f - %.2f ms (target: under 5 ms)\n", runs,
                quantile(p95s, 0.5), quantile(p95s, 0.0), quantile(p95s, 1.0));
}

} // namespace vox::bench
