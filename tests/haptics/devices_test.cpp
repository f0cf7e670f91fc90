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
}
