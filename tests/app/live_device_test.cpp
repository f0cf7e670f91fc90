// `voxsculpt run --device forcedimension|openhaptics`, as a user with a force-feedback device on
// the desk runs it, against the tests' fake vendor libraries (tests/haptics/fake_lib*.cpp): the
// run is real time (the haptic loop at 1 kHz of wall clock on its own thread), the device is given
// the coupling force pointing out of what the tool presses, never above its maximum; its second
// button switches the tool's action on; a device unplugged mid-run is said, given no force and
// taken up again; without the vendor's library the run fails before loading anything.

#include "app/run_command.hpp"
#include "test_support.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

using namespace vox::test;
namespace fs = std::filesystem;

namespace {

const std::string k_plate = VOX_SOURCE_DIR "/data/scenes/plate_probe.json";
const std::string k_knife = VOX_SOURCE_DIR "/data/scenes/press_and_cut.json";

struct ForceRow {
    double t_s = 0.0, z_mm = 0.0;
    double f[3] = {0, 0, 0};
    [[nodiscard]] double norm() const { return std::sqrt(f[0] * f[0] + f[1] * f[1] + f[2] * f[2]); }
};

std::vector<ForceRow> read_forces(const fs::path& csv)
{
    std::ifstream in(csv);
    std::string line;
    std::getline(in, line); // header
    std::vector<ForceRow> rows;
    while (std::getline(in, line)) {
        std::replace(line.begin(), line.end(), ',', ' ');
        std::istringstream s(line);
        ForceRow r;
        double x = 0.0, y = 0.0;
        s >> r.t_s >> x >> y >> r.z_mm >> r.f[0] >> r.f[1] >> r.f[2];
        rows.push_back(r);
    }
    return rows;
}

nlohmann::json read_stats(const fs::path& dir)
{
    std::ifstream in(dir / "stats.json");
    return nlohmann::json::parse(in);
}

/// The fake Force Dimension library in use, its device moving along `path` ("x y z vx vy vz", m
/// and m/s from where the tool starts); the other fake settings cleared.
void use_fake_dhd(const char* path)
{
    ::setenv("VOX_LIBDHD", VOX_FAKE_VENDOR_DIR "/libdhd.so", 1);
    ::setenv("FAKE_DHD_PATH", path, 1);
    for (const char* v : {"FAKE_DHD_FAULT", "FAKE_DHD_UNPLUG", "FAKE_DHD_BUTTON2", "FAKE_DHD_BUTTONS_FROM", "FAKE_DHD_COUNT"}) ::unsetenv(v);
}

} // namespace

TEST(LiveDevice, AForceDimensionDevicePressingAProbeIntoAStiffPlateFeelsItPushBackAtOneKilohertz)
{
    // The hand goes down 10 mm/s from 8 mm above the plate's top for 2 s: 12 mm past it.
    use_fake_dhd("0 0 0 0 0 -0.01");
    const fs::path d = fresh_dir("live_plate");
    const auto r = run_voxsculpt("run " + quote(k_plate) + " --device forcedimension --frames 200 --out " + quote((d / "out").string()));
    ASSERT_EQ(r.exit_code, 0) << r.err;
    EXPECT_NE(r.err.find("driven by the Force Dimension omega.6 (fake) device through a virtual coupling (1 kHz, real time)"), std::string::npos)
        << r.err;
    const nlohmann::json stats = read_stats(d / "out");
    const nlohmann::json& loop = stats["haptic_loop"];
    EXPECT_GT(loop["ticks"].get<double>(), 1800) << loop;
    EXPECT_NEAR(loop["rate_hz"].get<double>(), 1000.0, 50.0) << loop;
    EXPECT_EQ(stats["devices"][0]["device"], "Force Dimension omega.6 (fake)");
    EXPECT_EQ(stats["devices"][0]["faults"], 0);
    const std::vector<ForceRow> forces = read_forces(d / "out" / "forces.csv");
    ASSERT_GT(forces.size(), 1800u);
    double max_n = 0.0, min_z = 1e9;
    std::vector<double> up; // once the hand is 7 mm past the plate's top
    for (const ForceRow& f : forces) {
        max_n = std::max(max_n, f.norm());
        min_z = std::min(min_z, f.z_mm);
        if (f.t_s > 1.5) up.push_back(f.f[2]);
    }
    EXPECT_LE(max_n, 12.0 + 1e-6) << "the omega's maximum (dhdGetMaxForce; forces.csv keeps 9 digits)";
    ASSERT_FALSE(up.empty());
    std::sort(up.begin(), up.end());
    EXPECT_GT(up[up.size() / 2], 2.0) << "pressed past the top, the device is pushed back up, out of the plate (median)";
    // The probe (radius 2) stays on the plate, whose top is at 2 mm, while the hand goes far
    // below it; the plate bends under it by about a millimetre.
    EXPECT_GT(min_z, 2.0);
}

TEST(LiveDevice, TheSecondButtonSwitchesTheKnifesCutOnWhileHeld)
{
    // The knife goes down 8 mm/s for 2 s, from 10 mm above the block's top to 6 mm into it.
    for (const bool held : {false, true}) {
        use_fake_dhd("0 0 0 0 0 -0.008");
        if (held) ::setenv("FAKE_DHD_BUTTON2", "0 100000", 1);
        const fs::path d = fresh_dir(held ? "live_knife_held" : "live_knife");
        const auto r = run_voxsculpt("run " + quote(k_knife) + " --device forcedimension --frames 200 --out " + quote((d / "out").string()));
        ASSERT_EQ(r.exit_code, 0) << r.err;
        const nlohmann::json stats = read_stats(d / "out");
        if (held)
            EXPECT_GT(stats["summary"]["separated_faces"].get<long>(), 20) << "button 2 held: the knife cuts";
        else
            EXPECT_EQ(stats["summary"]["separated_faces"].get<long>(), 0) << "button 2 up: the knife only presses";
    }
    ::unsetenv("FAKE_DHD_BUTTON2");
}

TEST(LiveDevice, ADeviceUnpluggedMidRunIsSaidGivenNoForceAndTakenUpAgain)
{
    // The hand goes down 17.5 mm/s, on the plate from 0.5 s; the cable is pulled at poll 1500 (1.5 s)
    // and the device found again at the second try.
    use_fake_dhd("0 0 0 0 0 -0.0175");
    ::setenv("FAKE_DHD_UNPLUG", "1500 1", 1);
    const fs::path d = fresh_dir("live_unplug");
    const auto r = run_voxsculpt("run " + quote(k_plate) + " --device forcedimension --frames 400 --out " + quote((d / "out").string()));
    ::unsetenv("FAKE_DHD_UNPLUG");
    ASSERT_EQ(r.exit_code, 0) << r.err;
    EXPECT_NE(r.err.find("communication error between the host and the haptic device (fake): no force, the tool held where it was"), std::string::npos)
        << r.err;
    EXPECT_NE(r.err.find("answers again"), std::string::npos) << r.err;
    const nlohmann::json stats = read_stats(d / "out");
    EXPECT_EQ(stats["devices"][0]["faults"], 1);
    const std::vector<ForceRow> forces = read_forces(d / "out" / "forces.csv");
    double during = 0.0, after = 0.0;
    for (const ForceRow& f : forces) {
        if (f.t_s > 1.6 && f.t_s < 1.9) during = std::max(during, f.norm());
        if (f.t_s > 3.5) after = std::max(after, f.norm());
    }
    EXPECT_EQ(during, 0.0) << "no force while the device is away";
    EXPECT_GT(after, 1.0) << "back, the plate pushes again";
}

TEST(LiveDevice, WithoutTheVendorsLibraryTheRunFailsBeforeLoadingAnything)
{
    ::setenv("VOX_LIBHD", "/nonexistent/libHD.so", 1);
    const fs::path d = fresh_dir("live_missing");
    const auto r = run_voxsculpt("run " + quote(k_plate) + " --device openhaptics --out " + quote((d / "out").string()));
    ::unsetenv("VOX_LIBHD");
    EXPECT_EQ(r.exit_code, 2);
    EXPECT_NE(r.err.find("/nonexistent/libHD.so not found (from VOX_LIBHD)"), std::string::npos) << r.err;
    EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << "one line, before the object is loaded or the method built: " << r.err;
    EXPECT_FALSE(fs::exists(d / "out"));
}
