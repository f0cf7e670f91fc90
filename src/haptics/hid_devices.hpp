#pragma once
// HID devices through hidapi: what is connected, which of it can drive a tool, and, when nothing
// is found, why (no HID device at all, or /dev/hidraw* not readable by this user).

#include <cstdint>
#include <string>
#include <vector>

namespace vox::haptics {

struct HidDevice {
    std::uint16_t vendor_id = 0, product_id = 0;
    std::string path, manufacturer, product;
    bool six_dof = false; ///< a known 6-DoF controller (3Dconnexion's vendor ids)
    bool openable = false; ///< this user may open it (else a udev rule is missing)
};

/// The udev rule that lets the logged-in user open 3Dconnexion devices.
[[nodiscard]] std::string udev_rule_advice();

/// Every HID device hidapi enumerates. Throws InputError when hidapi cannot start.
[[nodiscard]] std::vector<HidDevice> enumerate_hid_devices();

/// Why enumeration came back empty, in one or more lines a user can act on (the udev rule to add
/// when /dev/hidraw* exists but cannot be opened).
[[nodiscard]] std::string explain_no_hid_devices();

} // namespace vox::haptics
