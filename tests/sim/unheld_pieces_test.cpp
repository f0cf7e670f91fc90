// What pieces no constraint holds do, on both methods: by default they stay where they are;
// "fall" lets them fall as free bodies (checked against implicit Euler's own free fall);
// "leave_out" drops them before the run.

#include "grid/label_grid.hpp"
#include "io/scene.hpp"
#include "io/scene_object.hpp"
#include "sim/frame_loop.hpp"
#include "sim/method_factory.hpp"
#include "sim/tool_policy.hpp"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <filesystem>

namespace fs = std::filesystem;

namespace vox::sim {
namespace {

/// Two blocks of 1 mm voxels, 4 mm apart along x: 8 x 4 x 4 from x = 0, 4 x 4 x 4 from x = 12.
fs::path two_blocks()
{
    const fs::path path = fs::path(::testing::TempDir()) / "two_blocks.vdb";
    grid::LabelGrid g;
    for (int k = 0; k < 4; ++k)
        for (int j = 0; j < 4; ++j) {
            for (int i = 0; i < 8; ++i) g.set({i, j, k}, 1);
            for (int i = 12; i < 16; ++i) g.set({i, j, k}, 1);
        }
    g.save(path);
    return path;
}

io::Scene scene(io::SolverType type, const char* unheld)
{
    nlohmann::json doc = {
        {"object", {{"volume", two_blocks().string()}, {"levels", 1}}},
        {"solver", {{"type", std::string(io::solver_type_name(type))}, {"dt_s", 0.01}}},
        {"gravity_m_s2", {0, 0, -9.81}},
        {"constraints", {{{"type", "fixed"}, {"box_mm", {{-1, -1, -1}, {0, 4, 4}}}}}},
    };
    if (unheld) doc["object"]["unheld_pieces"] = unheld;
    return io::parse_scene(doc, ::testing::TempDir(), "two_blocks.json");
}

/// Largest and smallest z displacement of the surface vertices of the block at x >= 11 after `frames` frames.
std::pair<double, double> loose_block_drop(const io::Scene& s, int frames, std::size_t* voxels = nullptr)
{
    auto labels = std::make_shared<const grid::LabelGrid>(io::load_scene_object(s));
    if (voxels) *voxels = labels->active_voxel_count();
    std::unique_ptr<Method> method = open_method(s, labels).method;
    ToolPolicy tools(s);
    FrameLoop loop(s, *method, tools);
    for (int f = 0; f < frames; ++f) loop.next();
    const surface::SurfaceMesh mesh = method->surface_mesh();
    const std::vector<Eigen::Vector3d> d = method->surface_displacements_mm();
    double lo = 1e300, hi = -1e300;
    for (std::size_t v = 0; v < d.size(); ++v)
        if (mesh.positions[v].x() - d[v].x() > 11.0) {
            lo = std::min(lo, d[v].z());
            hi = std::max(hi, d[v].z());
        }
    return {lo, hi};
}

class UnheldPieces : public ::testing::TestWithParam<io::SolverType> {};

TEST_P(UnheldPieces, StayWhereTheyAreByDefault)
{
    const auto [lo, hi] = loose_block_drop(scene(GetParam(), nullptr), 10);
    EXPECT_NEAR(lo, 0.0, 1e-9); // mm; exactly zero at the nodes, rounding in the embedding
    EXPECT_NEAR(hi, 0.0, 1e-9);
}

TEST_P(UnheldPieces, FallAsImplicitEulerFallsWhenAskedTo)
{
    // Implicit Euler with mass-proportional damping alpha: v' = (v + dt g) / (1 + alpha dt), x' = x + dt v'.
    const io::Scene s = scene(GetParam(), "fall");
    double v = 0.0, x = 0.0;
    for (int f = 0; f < 10; ++f) {
        v = (v - s.solver.dt_s * 9.81) / (1.0 + s.solver.rayleigh_mass_per_s * s.solver.dt_s);
        x += s.solver.dt_s * v;
    }
    const auto [lo, hi] = loose_block_drop(s, 10);
    EXPECT_NEAR(lo, 1e3 * x, 1e-3 * std::abs(1e3 * x)) << "free fall of a rigid block, mm";
    EXPECT_NEAR(hi, 1e3 * x, 1e-3 * std::abs(1e3 * x));
}

TEST_P(UnheldPieces, AreLeftOutWhenAskedTo)
{
    std::size_t voxels = 0;
    const io::Scene s = scene(GetParam(), "leave_out");
    const auto [lo, hi] = loose_block_drop(s, 1, &voxels);
    EXPECT_EQ(voxels, 8u * 4u * 4u);
    EXPECT_GT(lo, hi) << "no vertex of the loose block is left";
}

INSTANTIATE_TEST_SUITE_P(Methods, UnheldPieces, ::testing::Values(io::SolverType::dbg, io::SolverType::isxfem, io::SolverType::shape_matching),
                         [](const auto& method) { return std::string(io::solver_type_name(method.param)); });

} // namespace
} // namespace vox::sim
