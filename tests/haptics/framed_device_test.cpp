// A device's own frame placed in the scene (origin, turn, scale), and the clutch that lets the
// hand move without the tool (indexing), checked against the poses worked out by hand.

#include "haptics/framed_device.hpp"

#include <gtest/gtest.h>

#include <cmath>

using namespace vox::haptics;

namespace {
/// A hand whose pose and buttons the test sets, and that keeps the last force it was sent.
class Hand final : public Device {
public:
    [[nodiscard]] std::string name() const override { return "hand"; }
    [[nodiscard]] const DeviceLimits& limits() const override { return m_limits; }
    bool read(double t_s, DeviceState& state) noexcept override
    {
        state = pose;
        state.t_s = t_s;
        return true;
    }
    void send(const Eigen::Vector3d& force_n, const Eigen::Vector3d&) noexcept override { sent = force_n; }
    DeviceState pose;
    Eigen::Vector3d sent = Eigen::Vector3d::Constant(-1.0);

private:
    DeviceLimits m_limits;
};

const Eigen::Quaterniond k_quarter_z(Eigen::AngleAxisd(M_PI / 2, Eigen::Vector3d::UnitZ()));
} // namespace

TEST(FramedDevice, TheDevicesFrameIsPlacedTurnedAndScaledAndForcesGoBackTurnedNotScaled)
{
    Hand hand;
    FramedDevice framed(hand, {{10, 0, 0}, k_quarter_z, 2.0});
    DeviceState s;
    hand.pose.position_mm = {1, 0, 0};
    ASSERT_TRUE(framed.read(0.0, s));
    EXPECT_TRUE(s.position_mm.isApprox(Eigen::Vector3d(10, 2, 0), 1e-12)) << s.position_mm.transpose();
    EXPECT_TRUE(s.orientation.isApprox(k_quarter_z, 1e-12));
    framed.send({0, 3, 0}, Eigen::Vector3d::Zero()); // scene +y is the device's +x
    EXPECT_TRUE(hand.sent.isApprox(Eigen::Vector3d(3, 0, 0), 1e-12)) << hand.sent.transpose();
}

TEST(FramedDevice, TheClutchHoldsTheToolWhileTheHandMovesAndTheToolGoesOnFromThere)
{
    Hand hand;
    FramedDevice framed(hand, {{0, 0, 0}, Eigen::Quaterniond::Identity(), 1.0});
    DeviceState s;
    hand.pose.position_mm = {5, 0, 0};
    framed.read(0.0, s);
    EXPECT_EQ(s.position_mm, Eigen::Vector3d(5, 0, 0));
    // Clutch in, the hand goes back 40 mm and turns a quarter: the tool stays, no force.
    hand.pose.buttons = 1;
    hand.pose.position_mm = {-35, 0, 0};
    hand.pose.orientation = k_quarter_z;
    framed.read(0.001, s);
    EXPECT_TRUE(framed.clutched());
    EXPECT_EQ(s.position_mm, Eigen::Vector3d(5, 0, 0));
    EXPECT_TRUE(s.orientation.isApprox(Eigen::Quaterniond::Identity(), 1e-12));
    framed.send({1, 2, 3}, Eigen::Vector3d::Zero());
    EXPECT_EQ(hand.sent, Eigen::Vector3d::Zero());
    // Let go: the tool is still where it stayed, then follows the hand's moves from there.
    hand.pose.buttons = 0;
    framed.read(0.002, s);
    EXPECT_TRUE(s.position_mm.isApprox(Eigen::Vector3d(5, 0, 0), 1e-12));
    EXPECT_TRUE(s.orientation.isApprox(Eigen::Quaterniond::Identity(), 1e-12));
    hand.pose.position_mm = {-25, 0, 0};
    framed.read(0.003, s);
    EXPECT_TRUE(s.position_mm.isApprox(Eigen::Vector3d(15, 0, 0), 1e-12)) << s.position_mm.transpose();
    hand.pose.orientation = k_quarter_z * k_quarter_z; // the hand turns a further quarter: so does the tool
    framed.read(0.004, s);
    EXPECT_TRUE(s.orientation.isApprox(k_quarter_z, 1e-12));
    framed.send({1, 2, 3}, Eigen::Vector3d::Zero());
    EXPECT_EQ(hand.sent, Eigen::Vector3d(1, 2, 3));
}

TEST(FramedDevice, AClutchHeldFromTheFirstReadingHoldsTheToolWhereTheHandIs)
{
    Hand hand;
    FramedDevice framed(hand, {{100, 0, 0}, Eigen::Quaterniond::Identity(), 1.0});
    hand.pose.buttons = 1;
    hand.pose.position_mm = {0, 7, 0};
    DeviceState s; // the loop's first state: at the origin of the scene
    framed.read(0.0, s);
    EXPECT_EQ(s.position_mm, Eigen::Vector3d(100, 7, 0));
}
