// The force a device feels while its tool glides across the surface, pressed in at a constant
// depth, for each method: the tool crosses many particles (surface points, nodes, clusters) and
// the force must not jump as it does. Shape matching's force is its stable constraint particle
// coupling (docs/shape-matching.md); the finite-element methods' the penalty contact. The figure is
// the largest change of the force from one 1 kHz tick to the next, against the mean force.
#include "io/scene.hpp"
#include "io/scene_object.hpp"
#include "sim/device_run.hpp"
#include "sim/frame_loop.hpp"
#include "sim/method_factory.hpp"

#include <gtest/gtest.h>

#include <unistd.h>

#include <algorithm>
#include <filesystem>
#include <fstream>

namespace vox::sim {
namespace {

namespace fs = std::filesystem;

/// A block held at its base; a ball pressed 1 mm into its top, then drawn 24 mm along it in 1.2 s
/// (20 mm/s: a tick moves it 0.02 mm, twelve elements in all) and held.
fs::path write_scene(const std::string& solver)
{
    const fs::path dir = fs::temp_directory_path() / ("voxsculpt-glide-" + std::to_string(::getpid()) + "-" + solver);
    fs::create_directories(dir);
    const fs::path path = dir / "scene.json";
    std::ofstream(path) << R"({
        "object": {"phantom": {"shape": "beam", "size_mm": [40, 20, 10], "voxel_mm": 1.0}, "levels": 1},
        "materials": {"default": {"youngs_modulus_pa": 2e4, "poisson_ratio": 0.3, "density_kg_m3": 1000}},
        "solver": {"type": ")" << solver << R"(", "dt_s": 0.01},
        "gravity_m_s2": [0, 0, -9.81],
        "constraints": [{"type": "fixed", "box_mm": [[-1, -1, -1], [41, 21, 1]]}],
        "tools": [{"name": "ball", "shape": "sphere", "radius_mm": 3}],
        "script": [
            {"t_s": 0.0, "tool": "ball", "position_mm": [8, 10, 15]},
            {"t_s": 0.2, "tool": "ball", "position_mm": [8, 10, 12]},
            {"t_s": 0.4, "tool": "ball", "position_mm": [8, 10, 12]},
            {"t_s": 1.6, "tool": "ball", "position_mm": [32, 10, 12]},
            {"t_s": 1.8, "tool": "ball", "position_mm": [32, 10, 12]}
        ]
    })";
    return path;
}

struct Glide {
    double mean_force_n = 0.0;
    double largest_change_n = 0.0; ///< from one tick to the next, while gliding
    double p99_change_n = 0.0;
};

Glide glide(io::SolverType type)
{
    const io::Scene scene = io::load_scene(write_scene(std::string(io::solver_type_name(type))));
    auto method = open_method(scene, std::make_shared<const grid::LabelGrid>(io::load_scene_object(scene))).method;
    ToolPolicy tools(scene);
    DeviceRun device(scene, tools, DeviceOptions{});
    FrameLoop loop(scene, *method, tools, &device);
    for (int f = 0; f < 180; ++f) loop.next();
    Glide out;
    std::vector<double> changes;
    const std::vector<ForceSample>& forces = device.forces();
    for (std::size_t i = 1; i < forces.size(); ++i) {
        if (forces[i - 1].t_s < 0.5 || forces[i].t_s > 1.6) continue; // settled in, gliding
        changes.push_back((forces[i].force_n - forces[i - 1].force_n).norm());
        out.mean_force_n += forces[i].force_n.norm();
    }
    if (changes.empty()) return out;
    out.mean_force_n /= static_cast<double>(changes.size());
    std::sort(changes.begin(), changes.end());
    out.largest_change_n = changes.back();
    out.p99_change_n = changes[changes.size() * 99 / 100];
    return out;
}

class GlideOnEachMethod : public ::testing::TestWithParam<io::SolverType> {};

TEST_P(GlideOnEachMethod, TheForceChangesLittleFromTickToTickAsTheToolCrossesParticles)
{
    const Glide g = glide(GetParam());
    EXPECT_GT(g.mean_force_n, 0.05) << "the ball presses the block";
    // Measured: the device moves 0.02 mm a tick, the force's own rise over it is a few mN; a new
    // snapshot's move is spread over the frame (haptics/coupled_tool.hpp). p99 0.004 N on the
    // finite-element methods, 0.0011 N on shape matching.
    EXPECT_LT(g.p99_change_n, 0.01);
    if (GetParam() == io::SolverType::shape_matching) {
        // SCPC: the material's own stiffness on the clusters' goal surface. Measured 0.0015 N
        // (2 % of the force). The penalty contact of the finite-element methods catches now and
        // then as the ball crosses the surface's triangles (0.04 - 0.13 N once or twice a glide:
        // docs/haptics.md).
        EXPECT_LT(g.largest_change_n, 0.005);
        EXPECT_LT(g.largest_change_n, 0.05 * g.mean_force_n);
    }
}

INSTANTIATE_TEST_SUITE_P(Methods, GlideOnEachMethod,
                         ::testing::Values(io::SolverType::dbg, io::SolverType::isxfem, io::SolverType::shape_matching),
                         [](const auto& info) { return std::string(io::solver_type_name(info.param)); });

} // namespace
} // namespace vox::sim
