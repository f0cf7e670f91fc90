// Two devices at once, on every method: each drives its own tool through its own coupling, one
// haptic loop serves both, the recording holds both and replays bit for bit, and a recording
// from before several devices still replays on the tool asked for.
#include "core/error.hpp"
#include "haptics/recording.hpp"
#include "io/scene.hpp"
#include "io/scene_object.hpp"
#include "sim/device_run.hpp"
#include "sim/frame_loop.hpp"
#include "sim/method_factory.hpp"
#include "test_support.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <sstream>

namespace vox::sim {
namespace {

namespace fs = std::filesystem;
using test::fresh_dir;

/// A block held at its base; a ball presses its left end from the start, another its right end
/// from 0.15 s on.
fs::path write_scene(const fs::path& dir, const std::string& solver)
{
    const fs::path path = dir / "scene.json";
    std::ofstream(path) << R"({
        "object": {"phantom": {"shape": "beam", "size_mm": [40, 12, 8], "voxel_mm": 1.0}, "levels": 1},
        "materials": {"default": {"youngs_modulus_pa": 2e4, "poisson_ratio": 0.3, "density_kg_m3": 1000}},
        "solver": {"type": ")" << solver << R"(", "dt_s": 0.01},
        "constraints": [{"type": "fixed", "box_mm": [[-1, -1, -1], [41, 13, 1]]}],
        "tools": [{"name": "left", "shape": "sphere", "radius_mm": 3}, {"name": "right", "shape": "sphere", "radius_mm": 3}],
        "script": [
            {"t_s": 0.0, "tool": "left", "position_mm": [8, 6, 12]},
            {"t_s": 0.0, "tool": "right", "position_mm": [32, 6, 13]},
            {"t_s": 0.15, "tool": "left", "position_mm": [8, 6, 9.5]},
            {"t_s": 0.15, "tool": "right", "position_mm": [32, 6, 13]},
            {"t_s": 0.3, "tool": "left", "position_mm": [8, 6, 9.5]},
            {"t_s": 0.3, "tool": "right", "position_mm": [32, 6, 9.5]}
        ]
    })";
    return path;
}

struct Session {
    std::vector<std::vector<ForceSample>> forces; ///< per device
    std::vector<haptics::RecordedTick> recording;
};

Session run(const io::Scene& scene, const DeviceOptions& options, std::size_t frames = 30)
{
    auto method = open_method(scene, std::make_shared<const grid::LabelGrid>(io::load_scene_object(scene))).method;
    ToolPolicy tools(scene);
    DeviceRun device(scene, tools, options);
    FrameLoop loop(scene, *method, tools, &device);
    for (std::size_t f = 0; f < frames; ++f) loop.next();
    Session out;
    for (std::size_t i = 0; i < device.device_count(); ++i) out.forces.push_back(device.forces(i));
    out.recording = device.recording();
    return out;
}

class TwoDevicesOnEachMethod : public ::testing::TestWithParam<io::SolverType> {};

TEST_P(TwoDevicesOnEachMethod, EachDrivesItsToolAndTheRecordingReplaysBothBitForBit)
{
    const std::string name(io::solver_type_name(GetParam()));
    const fs::path dir = fresh_dir("two_devices_" + name);
    const io::Scene scene = io::load_scene(write_scene(dir, name));
    DeviceOptions two;
    two.tools = {"left", "right"};
    const Session live = run(scene, two);
    ASSERT_EQ(live.forces.size(), 2u);
    // Each hand felt its own press, the right one only once it came down (after 0.15 s).
    auto force_at = [](const std::vector<ForceSample>& f, double t) {
        return std::find_if(f.begin(), f.end(), [t](const ForceSample& s) { return s.t_s >= t - 1e-9; })->force_n.norm();
    };
    EXPECT_GT(force_at(live.forces[0], 0.14), 0.02);
    EXPECT_EQ(force_at(live.forces[1], 0.14), 0.0);
    EXPECT_GT(force_at(live.forces[1], 0.3), 0.02);
    EXPECT_LT(live.forces[0].back().position_mm.x(), 12.0);
    EXPECT_GT(live.forces[1].back().position_mm.x(), 28.0);
    // The recording holds both devices, tick by tick, with their tools.
    EXPECT_EQ(haptics::recorded_devices(live.recording), 2);
    EXPECT_EQ(live.recording.size(), 2u * (live.forces[0].size() + 1));
    EXPECT_EQ(live.recording[1].tool, "right");
    const fs::path recording = dir / "two.csv";
    haptics::write_recording(recording, live.recording);

    // Replayed: both tools where the recording puts them, every force bit for bit.
    DeviceOptions replay;
    replay.replay = recording;
    const Session again = run(scene, replay);
    ASSERT_EQ(again.forces.size(), 2u);
    for (std::size_t d = 0; d < 2; ++d) {
        ASSERT_EQ(again.forces[d].size(), live.forces[d].size());
        for (std::size_t k = 0; k < live.forces[d].size(); ++k) {
            ASSERT_EQ(again.forces[d][k].force_n, live.forces[d][k].force_n) << "device " << d << ", tick " << k;
            ASSERT_EQ(again.forces[d][k].position_mm, live.forces[d][k].position_mm) << "device " << d << ", tick " << k;
        }
    }

    // A recording from before several devices (no device or tool columns) replays on --tool.
    std::vector<haptics::RecordedTick> old = haptics::device_ticks(live.recording, 1);
    for (haptics::RecordedTick& t : old) {
        t.device = 0;
        t.tool.clear();
    }
    const fs::path old_path = dir / "old.csv";
    haptics::write_recording(old_path, old);
    {
        std::ifstream in(old_path);
        std::string header;
        std::getline(in, header);
        std::stringstream rest;
        rest << in.rdbuf();
        std::string text = rest.str(), rewritten;
        std::stringstream lines(text);
        for (std::string line; std::getline(lines, line);) rewritten += line.substr(0, line.rfind(',', line.rfind(',') - 1)) + "\n";
        std::ofstream(old_path) << "t_s,x_mm,y_mm,z_mm,qw,qx,qy,qz,buttons,fx_n,fy_n,fz_n,level,level_change\n" << rewritten;
    }
    DeviceOptions single;
    single.replay = old_path;
    single.tools = {"right"};
    const Session old_replay = run(scene, single);
    ASSERT_EQ(old_replay.forces.size(), 1u);
    EXPECT_GT(old_replay.forces[0].back().position_mm.x(), 28.0); // it drove the right ball
    EXPECT_GT(old_replay.forces[0].back().force_n.norm(), 0.02);
}

INSTANTIATE_TEST_SUITE_P(Methods, TwoDevicesOnEachMethod,
                         ::testing::Values(io::SolverType::dbg, io::SolverType::isxfem, io::SolverType::shape_matching),
                         [](const auto& method) { return std::string(io::solver_type_name(method.param)); });

TEST(TwoDevices, EachToolHasOneDevice)
{
    const fs::path dir = fresh_dir("two_devices_refused");
    const io::Scene scene = io::load_scene(write_scene(dir, "dbg"));
    ToolPolicy tools(scene);
    DeviceOptions o;
    o.tools = {"left", "left"};
    EXPECT_THROW(DeviceRun(scene, tools, o), InputError);
    o.tools = {"left", "spoon"};
    EXPECT_THROW(DeviceRun(scene, tools, o), InputError);
}

} // namespace
} // namespace vox::sim
