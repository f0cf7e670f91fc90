// The viewer's simulation thread driven without threads or a window, as the window and the
// haptic thread drive it: the proxy's pose through its triple buffer, the keys as requests. On
// both methods: a stroke cuts, U undoes it, pausing stops the frames, + changes the level, S saves.

#include "io/scene.hpp"
#include "io/scene_object.hpp"
#include "sim/dbg_method.hpp"
#include "sim/isxfem_method.hpp"
#include "sim/journal.hpp"
#include "sim/level_governor.hpp"
#include "test_support.hpp"
#include "haptics/force_devices.hpp"
#include "haptics/paced_device.hpp"
#include "view/view_simulation.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>

namespace vox::view {
namespace {

class ViewSimulationOnEachMethod : public ::testing::TestWithParam<io::SolverType> {};

TEST_P(ViewSimulationOnEachMethod, AStrokeCutsUndoPutsItBackAndTheKeysAreTaken)
{
    io::Scene scene = io::load_scene(VOX_SOURCE_DIR "/data/scenes/bar_cut_isxfem.json");
    io::use_method(scene, GetParam());
    scene.script.clear(); // the device moves the tool, as in the viewer
    auto labels = std::make_shared<const grid::LabelGrid>(io::load_scene_object(scene));
    std::unique_ptr<sim::Method> method;
    if (GetParam() == io::SolverType::dbg) method = std::make_unique<sim::DbgMethod>(scene, labels, 2, 3);
    else method = std::make_unique<sim::IsxfemMethod>(scene, labels, 2);
    sim::ToolPolicy tools(scene);
    ViewChannels channels(20000);
    ViewSimulationOptions options;
    options.grid_levels = 3;
    options.out_dir = vox::test::fresh_dir(std::string("view_simulation_") + (GetParam() == io::SolverType::dbg ? "dbg" : "isxfem"));
    ViewSimulation simulation(scene, std::move(method), tools, channels, options);
    ViewRequests& keys = channels.requests;
    const std::size_t dofs = simulation.method().dof_count();

    // The blade down through the bar, 1.2 mm a frame, as the haptic thread would report it.
    keys.stroke_started = true;
    const Eigen::Quaterniond turned(0.7071068, 0, 0, 0.7071068);
    for (int f = 0; f < 30; ++f) {
        channels.hand().proxies.write_slot() = {0, {&tools.shape(0), Eigen::Vector3d(50.3, 5, 20.5 - 1.2 * f), turned}, Eigen::Vector3d(50.3, 5, 19.3 - 1.2 * f)};
        channels.hand().proxies.publish();
        ASSERT_TRUE(simulation.step(0.01 * f));
    }
    EXPECT_GT(simulation.method().dof_count(), dofs) << "the stroke cut";
    EXPECT_EQ(simulation.history().size(), 1u);
    EXPECT_GT(channels.hand().snapshots.latest().count, 0u) << "the surface near the blade went to the haptic thread";
    EXPECT_TRUE(channels.pictures.update());
    EXPECT_FALSE(channels.pictures.read_slot().meshes.empty());

    keys.undo = true;
    ASSERT_TRUE(simulation.step(0.5));
    EXPECT_EQ(simulation.method().dof_count(), dofs) << "back to before the stroke";
    EXPECT_EQ(simulation.history().size(), 0u);

    keys.paused = true;
    EXPECT_FALSE(simulation.step(0.6)); // no frame while paused
    keys.step_once = true;
    EXPECT_TRUE(simulation.step(0.61)); // N: one
    keys.paused = false;

    keys.save_object = true;
    ASSERT_TRUE(simulation.step(0.7));
    EXPECT_TRUE(std::filesystem::exists(options.out_dir / "view_surface.obj"));

    keys.level_change = 1;
    ASSERT_TRUE(simulation.step(0.8));
    EXPECT_EQ(simulation.level(), 3);
    EXPECT_EQ(simulation.method().level(), 3);
    keys.level_change = 1; // beyond the grid's levels: stays
    ASSERT_TRUE(simulation.step(0.9));
    EXPECT_EQ(simulation.level(), 3);
}

TEST_P(ViewSimulationOnEachMethod, AStrokeIsJournaledWhenTheButtonGoesUpAndANewSessionResumesIt)
{
    const bool dbg = GetParam() == io::SolverType::dbg;
    const std::filesystem::path scene_file = VOX_SOURCE_DIR "/data/scenes/bar_cut_isxfem.json";
    io::Scene scene = io::load_scene(scene_file);
    io::use_method(scene, GetParam());
    scene.script.clear();
    auto labels = std::make_shared<const grid::LabelGrid>(io::load_scene_object(scene));
    const auto make = [&]() -> std::unique_ptr<sim::Method> {
        if (dbg) return std::make_unique<sim::DbgMethod>(scene, labels, 2, 3);
        return std::make_unique<sim::IsxfemMethod>(scene, labels, 2);
    };
    const std::filesystem::path dir = vox::test::fresh_dir(std::string("view_journal_") + (dbg ? "dbg" : "isxfem"));
    const std::filesystem::path journal = dir / "bar_cut_isxfem.journal";
    ViewSimulationOptions options; // both sessions journal to the same place
    options.out_dir = dir;
    options.journal = journal;
    options.scene_file = scene_file;
    std::size_t cuts = 0;
    std::vector<double> motion;
    {
        sim::ToolPolicy tools(scene);
        ViewChannels channels(20000);
        ViewSimulation simulation(scene, make(), tools, channels, options);
        channels.requests.stroke_started = true;
        const Eigen::Quaterniond turned(0.7071068, 0, 0, 0.7071068);
        for (int f = 0; f < 30; ++f) {
            channels.hand().proxies.write_slot() = {0, {&tools.shape(0), Eigen::Vector3d(50.3, 5, 20.5 - 1.2 * f), turned}, Eigen::Vector3d(50.3, 5, 19.3 - 1.2 * f)};
            channels.hand().proxies.publish();
            if (f == 29) channels.requests.stroke_ended = true; // the button goes up
            ASSERT_TRUE(simulation.step(0.01 * f));
        }
        cuts = simulation.method().cut_count();
        motion = simulation.method().motion();
        ASSERT_GT(cuts, 0u);
    } // the session ends (or the process dies): the journal is on disk

    // The next session with this scene: offered, not applied, until J.
    const sim::Journal earlier = sim::read_journal(journal, sim::journal_header(scene_file, *make()));
    ASSERT_FALSE(earlier.strokes.empty());
    sim::ToolPolicy tools(scene);
    ViewChannels channels(20000);
    options.offered = earlier;
    ViewSimulation simulation(scene, make(), tools, channels, options);
    ASSERT_TRUE(simulation.step(0.0));
    EXPECT_EQ(simulation.method().cut_count(), 0u);
    ASSERT_TRUE(channels.pictures.update());
    EXPECT_NE(channels.pictures.read_slot().notice.find("press J to resume"), std::string::npos);
    channels.requests.paused = true; // resumed exactly as it was: no frame stepped after it here
    channels.requests.resume = true;
    EXPECT_FALSE(simulation.step(0.01));
    EXPECT_EQ(simulation.method().cut_count(), cuts);
    EXPECT_EQ(simulation.method().motion(), motion);
    EXPECT_TRUE(std::filesystem::exists(dir / "bar_cut_isxfem.journal.previous")) << "the earlier journal kept aside";
    // The new session's journal holds the resumed cuts, so it can be resumed in turn.
    const sim::Journal now = sim::read_journal(journal, sim::journal_header(scene_file, simulation.method()));
    EXPECT_EQ(now.cuts(), earlier.cuts());
}

TEST(ViewSimulationLevels, ASessionOverBudgetMovesCoarserCarryingTheObjectAndSaysSo)
{
    io::Scene scene = io::load_scene(VOX_SOURCE_DIR "/data/scenes/bar_cut_isxfem.json");
    io::use_method(scene, io::SolverType::dbg);
    scene.script.clear();
    auto labels = std::make_shared<const grid::LabelGrid>(io::load_scene_object(scene));
    sim::ToolPolicy tools(scene);
    ViewChannels channels(20000);
    ViewSimulationOptions options;
    options.grid_levels = 3;
    options.out_dir = vox::test::fresh_dir("view_simulation_levels");
    options.journal = options.out_dir / "session.journal";
    options.scene_file = VOX_SOURCE_DIR "/data/scenes/bar_cut_isxfem.json";
    sim::LevelGovernor::Settings budget; // a budget no frame meets: coarser after each second
    budget.budget_ms = 1e-6;
    budget.dt_s = scene.solver.dt_s;
    budget.finest = 1;
    budget.coarsest = 3;
    options.governor = sim::LevelGovernor(budget);
    ViewSimulation simulation(scene, std::make_unique<sim::DbgMethod>(scene, labels, 1, 3), tools, channels, options);
    ViewRequests& keys = channels.requests;
    // The blade cuts into the bar, then the session runs on.
    keys.stroke_started = true;
    const Eigen::Quaterniond turned(0.7071068, 0, 0, 0.7071068);
    const int frames_per_second = static_cast<int>(std::lround(1.0 / scene.solver.dt_s));
    int moved_at = 0;
    for (int f = 0; f < 2 * frames_per_second && !moved_at; ++f) {
        const double depth = std::min(f, 12) * 1.2;
        channels.hand().proxies.write_slot() = {0, {&tools.shape(0), Eigen::Vector3d(50.3, 5, 20.5 - depth), turned}, Eigen::Vector3d(50.3, 5, 20.5 - depth)};
        channels.hand().proxies.publish();
        keys.picture_taken = true;
        ASSERT_TRUE(simulation.step(0.01 * f));
        if (simulation.level() == 2) moved_at = f + 1;
    }
    ASSERT_GT(moved_at, 0) << "a second of frames over budget (at most 100 frames of 10 ms: fewer when frames take longer)";
    EXPECT_EQ(simulation.method().level(), 2);
    EXPECT_GT(simulation.method().cut_count(), 0u) << "the cuts kept";
    EXPECT_EQ(simulation.history().size(), 1u) << "the undo history kept";
    ASSERT_TRUE(channels.pictures.update());
    EXPECT_NE(channels.pictures.read_slot().model.find(", level 2"), std::string::npos) << channels.pictures.read_slot().model;
    EXPECT_EQ(channels.pictures.read_slot().notice.rfind("level 1 -> 2: frames over budget", 0), 0u) << channels.pictures.read_slot().notice;
    // The journal started again at the new level, its first line holding the cuts so far.
    sim::JournalHeader header = sim::journal_header(options.scene_file, simulation.method());
    const sim::Journal journal = sim::read_journal(options.journal, header);
    EXPECT_EQ(journal.header.level, 2);
    EXPECT_EQ(journal.cuts().size(), simulation.method().cut_count());
    // Undo goes back to before the stroke, at the level it began at.
    keys.undo = true;
    ASSERT_TRUE(simulation.step(3.0));
    EXPECT_EQ(simulation.level(), 1);
    EXPECT_EQ(simulation.method().cut_count(), 0u);
}

TEST(ViewSimulationHands, TwoDevicesEachDriveTheirOwnToolAndGetTheSurfaceNearIt)
{
    // data/scenes/two_hands.json: a finger presses the block's left while a knife cuts its right,
    // each through its own hand's channel, as the haptic thread reports them.
    io::Scene scene = io::load_scene(VOX_SOURCE_DIR "/data/scenes/two_hands.json");
    scene.script.clear();
    auto labels = std::make_shared<const grid::LabelGrid>(io::load_scene_object(scene));
    sim::ToolPolicy tools(scene);
    ViewChannels channels(20000, 2);
    ViewSimulationOptions options;
    options.grid_levels = 2;
    options.out_dir = vox::test::fresh_dir("view_simulation_hands");
    options.hands = {{0, Eigen::Vector3d(11.5, 11.5, 19), "script"}, {1, Eigen::Vector3d(33.5, 12, 22), "mouse"}};
    ViewSimulation simulation(scene, std::make_unique<sim::DbgMethod>(scene, labels, 1, 2), tools, channels, options);
    for (int f = 0; f < 60; ++f) {
        const Eigen::Vector3d finger(11.5, 11.5, std::max(19.0 - 0.25 * f, 14.5)), knife(33.5, 12, std::max(22.0 - 0.3 * f, 6.0));
        channels.hand(0).proxies.write_slot() = {0, {&tools.shape(0), finger, Eigen::Quaterniond::Identity()}, finger};
        channels.hand(0).proxies.publish();
        channels.hand(1).proxies.write_slot() = {1, {&tools.shape(1), knife, Eigen::Quaterniond::Identity()}, knife};
        channels.hand(1).proxies.publish();
        ASSERT_TRUE(simulation.step(0.01 * f));
    }
    EXPECT_EQ(tools.placed(0).position.z(), 14.5);
    EXPECT_EQ(tools.placed(1).position.z(), 6.0);
    EXPECT_GT(simulation.method().cut_count(), 0u) << "the knife cut";
    // The finger pressed the top (z = 12 at rest) down under it.
    double lowest = INFINITY;
    const surface::SurfaceMesh mesh = simulation.method().surface_mesh();
    for (const Eigen::Vector3d& p : mesh.positions)
        if (std::abs(p.x() - 11.5) < 1.5 && std::abs(p.y() - 11.5) < 1.5 && p.z() > 6.0) lowest = std::min(lowest, p.z());
    EXPECT_LT(lowest, 11.5);
    // Each hand's snapshot is the surface near its own tool, and the clock the scripted ones follow moved on.
    for (std::size_t d = 0; d < 2; ++d) {
        const contact::SurfacePoints& snapshot = channels.hand(d).snapshots.latest();
        ASSERT_GT(snapshot.count, 0u) << "hand " << d;
        const double x = tools.placed(d).position.x();
        for (std::size_t i = 0; i < snapshot.count; ++i) EXPECT_LT(std::abs(snapshot.positions_mm[i].x() - x), 20.0) << "hand " << d;
    }
    EXPECT_NEAR(channels.simulation_t_s.load(), 0.6, 1e-9);
}

/// A force-feedback device as the viewer's simulation sees it: a fault it can be told to have,
/// and how often it was asked to come back.
class FaultyDevice final : public haptics::Device {
public:
    [[nodiscard]] std::string name() const override { return "omega.6"; }
    [[nodiscard]] const haptics::DeviceLimits& limits() const override { return m_limits; }
    bool read(double, haptics::DeviceState&) noexcept override { return false; }
    [[nodiscard]] const char* fault() const noexcept override { return m_fault; }
    void recover() override { ++recovers; }
    const char* m_fault = nullptr;
    int recovers = 0;

private:
    haptics::DeviceLimits m_limits;
};

TEST(ViewSimulationHands, TheSecondButtonSwitchesTheActionOnAndAFaultIsShownUntilTheDeviceAnswers)
{
    io::Scene scene = io::load_scene(VOX_SOURCE_DIR "/data/scenes/bar_cut_isxfem.json");
    io::use_method(scene, io::SolverType::dbg);
    scene.script.clear();
    auto labels = std::make_shared<const grid::LabelGrid>(io::load_scene_object(scene));
    FaultyDevice device;
    ViewSimulationOptions options;
    options.grid_levels = 3;
    options.hands = {ViewHand{0, Eigen::Vector3d(50.3, 5, 30), "forcedimension", &device, true}};
    const Eigen::Quaterniond turned(0.7071068, 0, 0, 0.7071068);
    // The blade down through the bar, its second button up or held throughout, on a bar of its own.
    for (const std::uint32_t buttons : {0u, haptics::k_action_button}) {
        sim::ToolPolicy tools(scene);
        ViewChannels channels(20000);
        ViewSimulation simulation(scene, std::make_unique<sim::DbgMethod>(scene, labels, 2, 3), tools, channels, options);
        const std::size_t dofs = simulation.method().dof_count();
        for (int f = 0; f < 30; ++f) {
            channels.hand().proxies.write_slot() = {0, {&tools.shape(0), Eigen::Vector3d(50.3, 5, 20.5 - 1.2 * f), turned},
                                                    Eigen::Vector3d(50.3, 5, 19.3 - 1.2 * f), 0.5, buttons};
            channels.hand().proxies.publish();
            ASSERT_TRUE(simulation.step(0.01 * f));
        }
        EXPECT_EQ(tools.armed(0), buttons != 0u);
        if (buttons == 0u) {
            EXPECT_EQ(simulation.method().dof_count(), dofs) << "no cut with the button up";
            continue;
        }
        EXPECT_GT(simulation.method().dof_count(), dofs) << "held, the blade cuts";

        // A cable pulled: said on screen, the device asked to come back each frame, until it answers.
        device.m_fault = "communication error (fake)";
        ASSERT_TRUE(simulation.step(2.0));
        channels.requests.picture_taken = true;
        ASSERT_TRUE(simulation.step(2.01));
        ASSERT_TRUE(channels.pictures.update());
        EXPECT_NE(channels.pictures.read_slot().notice.find("omega.6: communication error (fake): no force"), std::string::npos)
            << channels.pictures.read_slot().notice;
        EXPECT_EQ(device.recovers, 2);
        device.m_fault = nullptr;
        channels.requests.picture_taken = true;
        ASSERT_TRUE(simulation.step(2.02));
        ASSERT_TRUE(channels.pictures.update());
        EXPECT_EQ(channels.pictures.read_slot().notice, "");
        EXPECT_EQ(device.recovers, 2);
    }
}

TEST(PacedDevice, FollowsItsScriptInSimulatedTimeRunningOnAtMostOneFrame)
{
    std::atomic<double> simulated{0.0};
    haptics::PacedDevice device({{0.0, Eigen::Vector3d(0, 0, 0), Eigen::Quaterniond::Identity()}, {1.0, Eigen::Vector3d(10, 0, 0), Eigen::Quaterniond::Identity()}},
                       simulated, 0.01);
    haptics::DeviceState s;
    device.read(5.0, s); // the loop's clock is not the simulation's
    EXPECT_NEAR(s.position_mm.x(), 0.0, 1e-12);
    EXPECT_EQ(s.t_s, 5.0);
    device.read(5.004, s); // runs on with the loop between frames
    EXPECT_NEAR(s.position_mm.x(), 0.04, 1e-9);
    device.read(5.5, s); // but not past one frame while the simulation stands still (paused, slow)
    EXPECT_NEAR(s.position_mm.x(), 0.1, 1e-9);
    simulated = 0.5;
    device.read(5.501, s);
    EXPECT_NEAR(s.position_mm.x(), 5.0, 1e-9);
}

INSTANTIATE_TEST_SUITE_P(Methods, ViewSimulationOnEachMethod, ::testing::Values(io::SolverType::dbg, io::SolverType::isxfem),
                         [](const auto& info) { return std::string(info.param == io::SolverType::dbg ? "dbg" : "isxfem"); });

} // namespace
} // namespace vox::view
