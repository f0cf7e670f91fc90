// The scripted and replay devices, and the recording format they share with the haptic loop.

#include "core/error.hpp"
#include "haptics/recording.hpp"
#include "haptics/virtual_device.hpp"
#include "test_support.hpp"

#include <gtest/gtest.h>

#include <fstream>

using namespace vox::haptics;
using Eigen::Quaterniond;
using Eigen::Vector3d;

TEST(VirtualDevice, InterpolatesPositionAndSlerpsOrientation)
{
    const Quaterniond turned(Eigen::AngleAxisd(M_PI / 2, Vector3d::UnitZ()));
    VirtualDevice d({{0.0, {0, 0, 0}, Quaterniond::Identity()}, {2.0, {10, 20, -4}, turned}});
    DeviceState s;
    ASSERT_TRUE(d.read(0.5, s));
    EXPECT_TRUE(s.position_mm.isApprox(Vector3d(2.5, 5, -1)));
    EXPECT_NEAR(s.orientation.angularDistance(Quaterniond::Identity()), M_PI / 8, 1e-12);
    d.read(-1.0, s); // held before the first frame
    EXPECT_EQ(s.position_mm, Vector3d::Zero());
    d.read(9.0, s); // and after the last
    EXPECT_EQ(s.position_mm, Vector3d(10, 20, -4));
    EXPECT_FALSE(d.limits().force_output);
    EXPECT_EQ(d.limits().workspace_max_mm, Vector3d(10, 20, 0));
    EXPECT_THROW(VirtualDevice({{1.0, {0, 0, 0}, Quaterniond::Identity()}, {0.5, {0, 0, 0}, Quaterniond::Identity()}}), vox::InputError);
}

TEST(Recording, RoundTripsExactlyAndReplays)
{
    std::vector<RecordedTick> ticks;
    for (int k = 0; k < 50; ++k) {
        RecordedTick t;
        t.state.t_s = k * 1e-3;
        t.state.position_mm = Vector3d(std::sin(k * 0.1), 1.0 / 3.0 * k, -k * 1e-7);
        t.state.orientation = Quaterniond(Eigen::AngleAxisd(0.01 * k, Vector3d(1, 2, 3).normalized()));
        t.state.buttons = static_cast<std::uint32_t>(k % 3);
        t.force_n = Vector3d(0.1 * k, -std::sqrt(2.0), 1e-300);
        ticks.push_back(t);
    }
    const auto path = vox::test::fresh_dir("recording") / "session.csv";
    write_recording(path, ticks);
    const auto back = read_recording(path);
    ASSERT_EQ(back.size(), ticks.size());
    for (std::size_t i = 0; i < ticks.size(); ++i) { // bit for bit
        EXPECT_EQ(back[i].state.t_s, ticks[i].state.t_s);
        EXPECT_EQ(back[i].state.position_mm, ticks[i].state.position_mm);
        EXPECT_EQ(back[i].state.orientation.coeffs(), ticks[i].state.orientation.coeffs());
        EXPECT_EQ(back[i].state.buttons, ticks[i].state.buttons);
        EXPECT_EQ(back[i].force_n, ticks[i].force_n);
    }
    ReplayDevice replay(back);
    DeviceState s;
    replay.read(0.0105, s); // between ticks 10 and 11: the last one at or before
    EXPECT_EQ(s.position_mm, ticks[10].state.position_mm);
    replay.read(0.003, s); // time may jump back (a restart)
    EXPECT_EQ(s.position_mm, ticks[3].state.position_mm);
}

TEST(Recording, MalformedFilesNameTheFileAndLine)
{
    const auto dir = vox::test::fresh_dir("recording_bad");
    const std::string header = "t_s,x_mm,y_mm,z_mm,qw,qx,qy,qz,buttons,fx_n,fy_n,fz_n\n";
    auto refused = [&](const std::string& name, const std::string& text, const std::string& problem) {
        std::ofstream(dir / name) << text;
        try {
            static_cast<void>(read_recording(dir / name));
            ADD_FAILURE() << name << " was accepted";
        } catch (const vox::InputError& e) {
            EXPECT_NE(std::string(e.what()).find((dir / name).string()), std::string::npos) << e.what();
            EXPECT_NE(std::string(e.what()).find(problem), std::string::npos) << e.what();
        }
    };
    refused("header.csv", "time,x\n", "line 1: expected the header");
    refused("fields.csv", header + "0,1,2,3,1,0,0,0,0,0,0\n", "line 2: expected 12 comma-separated fields, got 11");
    refused("nan.csv", header + "0,nan,2,3,1,0,0,0,0,0,0,0\n", "line 2: field 2");
    refused("quaternion.csv", header + "0,1,2,3,2,0,0,0,0,0,0,0\n", "not a unit quaternion");
    refused("backwards.csv", header + "1,1,2,3,1,0,0,0,0,0,0,0\n0.5,1,2,3,1,0,0,0,0,0,0,0\n", "line 3: time goes backwards");
    refused("buttons.csv", header + "0,1,2,3,1,0,0,0,1.5,0,0,0\n", "buttons must be a whole number");
    refused("empty.csv", "", "is empty");
    refused("no_ticks.csv", header, "holds no tick");
    const std::string header_devices = "t_s,x_mm,y_mm,z_mm,qw,qx,qy,qz,buttons,fx_n,fy_n,fz_n,level,level_change,device,tool\n";
    refused("device.csv", header_devices + "0,1,2,3,1,0,0,0,0,0,0,0,1,,x,knife\n", "line 2: device (\"x\") must be a whole number from 0 to 7");
    refused("device_range.csv", header_devices + "0,1,2,3,1,0,0,0,0,0,0,0,1,,8,knife\n", "from 0 to 7");
    refused("device_fields.csv", header_devices + "0,1,2,3,1,0,0,0,0,0,0,0,1,,0\n", "expected 16 comma-separated fields, got 15");
}

TEST(Recording, HoldsEveryDeviceAndReadsRecordingsFromBefore)
{
    // Two devices, tick by tick, each with the tool it drove; read back as written, and each
    // device's ticks apart for its replay.
    std::vector<RecordedTick> ticks;
    for (int k = 0; k < 20; ++k)
        for (int d = 0; d < 2; ++d) {
            RecordedTick t;
            t.state.t_s = k * 1e-3;
            t.state.position_mm = Vector3d(d, k, 0.1 * k * (d + 1));
            t.force_n = Vector3d(0, 0, 0.01 * k);
            t.level = 2;
            t.device = d;
            t.tool = d == 0 ? "scalpel" : "finger";
            ticks.push_back(t);
        }
    ticks[7].level_change = "as asked, with a comma"; // commas become semicolons
    const auto dir = vox::test::fresh_dir("recording_devices");
    write_recording(dir / "two.csv", ticks);
    const auto back = read_recording(dir / "two.csv");
    ASSERT_EQ(back.size(), ticks.size());
    EXPECT_EQ(recorded_devices(back), 2);
    for (std::size_t i = 0; i < ticks.size(); ++i) {
        EXPECT_EQ(back[i].device, ticks[i].device);
        EXPECT_EQ(back[i].tool, ticks[i].tool);
        EXPECT_EQ(back[i].state.position_mm, ticks[i].state.position_mm);
        EXPECT_EQ(back[i].level, 2);
    }
    EXPECT_EQ(back[7].level_change, "as asked; with a comma");
    const std::vector<RecordedTick> finger = device_ticks(back, 1);
    ASSERT_EQ(finger.size(), 20u);
    ReplayDevice replay(finger);
    DeviceState s;
    replay.read(0.0125, s);
    EXPECT_EQ(s.position_mm, ticks[2 * 12 + 1].state.position_mm); // tick 12, the last at or before
    // Recordings from before several devices (with and without the level columns) are one device
    // that named no tool.
    std::ofstream(dir / "v2.csv") << "t_s,x_mm,y_mm,z_mm,qw,qx,qy,qz,buttons,fx_n,fy_n,fz_n,level,level_change\n"
                                     "0,1,2,3,1,0,0,0,0,0,0,0,3,\n0.001,1,2,4,1,0,0,0,0,0,0,0,4,over budget\n";
    std::ofstream(dir / "v1.csv") << "t_s,x_mm,y_mm,z_mm,qw,qx,qy,qz,buttons,fx_n,fy_n,fz_n\n0,1,2,3,1,0,0,0,0,0,0,0\n";
    for (const char* name : {"v2.csv", "v1.csv"}) {
        const auto old = read_recording(dir / name);
        EXPECT_EQ(recorded_devices(old), 1) << name;
        EXPECT_EQ(old.front().device, 0);
        EXPECT_TRUE(old.front().tool.empty());
    }
    EXPECT_EQ(read_recording(dir / "v2.csv").back().level_change, "over budget");
}
