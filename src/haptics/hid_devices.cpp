#include "haptics/hid_devices.hpp"

#include "core/error.hpp"

#include <hidapi.h>

#include <filesystem>
#include <unistd.h>

namespace vox::haptics {
namespace {

std::string narrow(const wchar_t* text)
{
    std::string out;
    for (; text && *text; ++text) out += (*text >= 32 && *text < 127) ? static_cast<char>(*text) : '?';
    return out;
}

} // namespace

std::vector<HidDevice> enumerate_hid_devices()
{
    if (hid_init() != 0) throw InputError("HID: hidapi could not start (hid_init failed)");
    std::vector<HidDevice> out;
    hid_device_info* list = hid_enumerate(0, 0);
    for (const hid_device_info* d = list; d; d = d->next) {
        HidDevice h;
        h.vendor_id = d->vendor_id;
        h.product_id = d->product_id;
        h.path = d->path ? d->path : "";
        h.manufacturer = narrow(d->manufacturer_string);
        h.product = narrow(d->product_string);
        // 3Dconnexion (0x256f) and its Logitech-era devices (0x046d, products 0xc6xx).
        h.six_dof = h.vendor_id == 0x256f || (h.vendor_id == 0x046d && (h.product_id & 0xff00) == 0xc600);
        if (hid_device* handle = hid_open_path(d->path)) {
            h.openable = true;
            hid_close(handle);
        }
        out.push_back(h);
    }
    hid_free_enumeration(list);
    hid_exit();
    return out;
}

std::string explain_no_hid_devices()
{
    std::vector<std::filesystem::path> nodes;
    std::error_code ec;
    for (const auto& entry : std::filesystem::directory_iterator("/dev", ec))
        if (entry.path().filename().string().rfind("hidraw", 0) == 0) nodes.push_back(entry.path());
    if (nodes.empty())
        return "no HID devices: /dev has no hidraw nodes (nothing is plugged in, or this machine or container "
               "has no USB HID access); headless runs still move the tool along the scene script";
    std::string unreadable;
    for (const auto& n : nodes)
        if (::access(n.c_str(), R_OK | W_OK) != 0) unreadable += (unreadable.empty() ? "" : ", ") + n.string();
    if (!unreadable.empty()) return "HID devices exist but this user may not open them (" + unreadable + "). " + udev_rule_advice();
    return "hidraw nodes are readable but hidapi lists no device";
}

std::string udev_rule_advice()
{
    return "Add a udev rule, e.g. /etc/udev/rules.d/70-voxsculpt.rules with\n"
           "  KERNEL==\"hidraw*\", ATTRS{idVendor}==\"256f\", MODE=\"0660\", TAG+=\"uaccess\"\n"
           "then run: sudo udevadm control --reload-rules && sudo udevadm trigger, and replug the device";
}

} // namespace vox::haptics
