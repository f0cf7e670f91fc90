// SpaceMouse-class HID reports: both report layouts, buttons, unknown reports, and the axis
// mapping (dead zone, sign, clamping).

#include "haptics/spacemouse_device.hpp"
#include "haptics/spacemouse_report.hpp"

#include <gtest/gtest.h>

#include <vector>

using namespace vox::haptics;

namespace {
std::vector<std::uint8_t> report(std::uint8_t id, std::initializer_list<std::int16_t> values)
{
    std::vector<std::uint8_t> r{id};
    for (std::int16_t v : values) {
        r.push_back(static_cast<std::uint8_t>(static_cast<std::uint16_t>(v) & 0xff));
        r.push_back(static_cast<std::uint8_t>(static_cast<std::uint16_t>(v) >> 8));
    }
    return r;
}
} // namespace

TEST(SpaceMouseReport, SeparateTranslationRotationAndButtonReports)
{
    SixAxisState s;
    ASSERT_TRUE(parse_spacemouse_report(report(1, {100, -200, 350}), s));
    ASSERT_TRUE(parse_spacemouse_report(report(2, {-1, 32767, -32768}), s));
    EXPECT_EQ(s.axes, (std::array<std::int16_t, 6>{100, -200, 350, -1, 32767, -32768}));
    const std::vector<std::uint8_t> buttons{3, 0x05, 0x01};
    ASSERT_TRUE(parse_spacemouse_report(buttons, s));
    EXPECT_EQ(s.buttons, 0x105u);
}

TEST(SpaceMouseReport, SingleThirteenByteReportCarriesAllAxes)
{
    SixAxisState s;
    ASSERT_TRUE(parse_spacemouse_report(report(1, {1, 2, 3, 4, 5, 6}), s));
    EXPECT_EQ(s.axes, (std::array<std::int16_t, 6>{1, 2, 3, 4, 5, 6}));
}

TEST(SpaceMouseReport, UnknownOrShortReportsChangeNothing)
{
    SixAxisState s;
    s.axes = {7, 7, 7, 7, 7, 7};
    const SixAxisState before = s;
    EXPECT_FALSE(parse_spacemouse_report(report(4, {1, 2, 3}), s));
    EXPECT_FALSE(parse_spacemouse_report(std::vector<std::uint8_t>{1, 0, 0}, s));
    EXPECT_FALSE(parse_spacemouse_report(std::vector<std::uint8_t>{}, s));
    EXPECT_EQ(s.axes, before.axes);
}

TEST(SpaceMouseReport, MappingAppliesTableDeadZoneAndClamp)
{
    SixAxisState s;
    s.axes = {10, -366, 1000, 0, 0, 183};
    AxisMapping m;
    m.source = {1, 0, 2, 3, 4, 5}; // swap x and y
    m.sign = {1, 1, -1, 1, 1, 1};  // z points the other way
    m.dead_zone = 16;
    m.full_scale = 366;
    const auto out = map_axes(s, m);
    EXPECT_DOUBLE_EQ(out[0], -1.0);                   // raw y = -366: full scale
    EXPECT_DOUBLE_EQ(out[1], 0.0);                    // raw x = 10: inside the dead zone
    EXPECT_DOUBLE_EQ(out[2], -1.0);                   // 1000 clamps to 1, sign flipped
    EXPECT_DOUBLE_EQ(out[5], (183.0 - 16) / (366 - 16)); // continuous past the dead zone
}

TEST(SpaceMouseRateControl, FullDeflectionMovesAndTurnsAtTheSetRates)
{
    // Half a second at full +x deflection: 30 mm at 60 mm/s; a second at full rz: 90 degrees
    // about z at 90 degrees/s, in ten steps as the loop would take them.
    Eigen::Vector3d p = Eigen::Vector3d::Zero();
    Eigen::Quaterniond q = Eigen::Quaterniond::Identity();
    for (int i = 0; i < 10; ++i) vox::haptics::integrate_six_dof({1, 0, 0, 0, 0, 0}, 0.05, {}, p, q);
    EXPECT_NEAR(p.x(), 30.0, 1e-9);
    EXPECT_NEAR(p.tail<2>().norm(), 0.0, 1e-12);
    for (int i = 0; i < 10; ++i) vox::haptics::integrate_six_dof({0, 0, 0, 0, 0, 1}, 0.1, {}, p, q);
    EXPECT_NEAR(q.angularDistance(Eigen::Quaterniond(Eigen::AngleAxisd(M_PI / 2, Eigen::Vector3d::UnitZ()))), 0.0, 1e-9);
    EXPECT_NEAR(p.x(), 30.0, 1e-9); // turning does not move it
    // A cap at rest inside the dead zone does nothing.
    vox::haptics::SixAxisState raw;
    raw.axes = {10, -12, 5, 0, 3, -15};
    const Eigen::Vector3d before = p;
    vox::haptics::integrate_six_dof(vox::haptics::map_axes(raw, {}), 1.0, {}, p, q);
    EXPECT_EQ(p, before);
}
