// voxsculpt devices: every kind of input device the program can drive a tool with (HID
// controllers, OpenHaptics and Force Dimension force-feedback devices) and, for each, the devices
// found or why there are none.

#include "app/commands.hpp"
#include "haptics/forcedimension_device.hpp"
#include "haptics/hid_devices.hpp"
#include "haptics/openhaptics_device.hpp"

#include <CLI/CLI.hpp>

#include <cstdio>

namespace vox::app {

namespace {
void print_hid()
{
    std::printf("HID controllers (--device hid in view):\n");
    const auto devices = haptics::enumerate_hid_devices();
    if (devices.empty()) {
        std::printf("  %s\n", haptics::explain_no_hid_devices().c_str());
        return;
    }
    bool blocked = false;
    for (const haptics::HidDevice& d : devices) {
        std::printf("  %04x:%04x  %-12s %-28s %s%s\n", d.vendor_id, d.product_id, d.manufacturer.c_str(), d.product.c_str(),
                    d.six_dof ? "6-DoF controller: drives the tool" : "not a tool device", d.openable ? "" : " (cannot be opened by this user)");
        blocked = blocked || (d.six_dof && !d.openable);
    }
    if (blocked) std::printf("  %s\n", haptics::udev_rule_advice().c_str());
}

void print_force_device(const haptics::ForceDeviceInfo& d)
{
    if (!d.problem.empty()) {
        std::printf("  none: %s\n", d.problem.c_str());
        return;
    }
    std::printf("  %s%s%s, maximum force %.2f N\n", d.model.c_str(), d.serial.empty() ? "" : ", serial ", d.serial.c_str(), d.max_force_n);
}
} // namespace

void add_devices_command(CLI::App& app)
{
    CLI::App* cmd = app.add_subcommand("devices", "List the input devices found, by kind (HID 6-DoF controllers, OpenHaptics and "
                                                  "Force Dimension force-feedback devices), or say why there are none");
    cmd->callback([] {
        print_hid();
        std::printf("OpenHaptics (--device openhaptics; libHD.so or VOX_LIBHD):\n");
        print_force_device(haptics::OpenHapticsDevice::probe());
        std::printf("Force Dimension (--device forcedimension; libdhd.so or VOX_LIBDHD):\n");
        for (const haptics::ForceDeviceInfo& d : haptics::ForceDimensionDevice::probe()) print_force_device(d);
    });
}

} // namespace vox::app
