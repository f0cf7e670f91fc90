// voxsculpt devices: the input devices found and which can drive a tool; when none is found, why.

#include "app/commands.hpp"
#include "haptics/hid_devices.hpp"

#include <CLI/CLI.hpp>

#include <cstdio>

namespace vox::app {

void add_devices_command(CLI::App& app)
{
    CLI::App* cmd = app.add_subcommand("devices", "List HID input devices (6-DoF controllers drive the tool) or say why there are none");
    cmd->callback([] {
        const auto devices = haptics::enumerate_hid_devices();
        if (devices.empty()) {
            std::printf("%s\n", haptics::explain_no_hid_devices().c_str());
            return;
        }
        bool blocked = false;
        for (const haptics::HidDevice& d : devices) {
            std::printf("%04x:%04x  %-12s %-28s %s%s\n", d.vendor_id, d.product_id, d.manufacturer.c_str(), d.product.c_str(),
                        d.six_dof ? "6-DoF controller: drives the tool" : "not a tool device",
                        d.openable ? "" : " (cannot be opened by this user)");
            blocked = blocked || (d.six_dof && !d.openable);
        }
        if (blocked) std::printf("%s\n", haptics::udev_rule_advice().c_str());
    });
}

} // namespace vox::app
