#include "haptics/force_devices.hpp"

#include "core/error.hpp"
#include "haptics/forcedimension_device.hpp"
#include "haptics/openhaptics_device.hpp"

namespace vox::haptics {

bool is_force_device(const std::string& kind) { return kind == "openhaptics" || kind == "forcedimension"; }

std::unique_ptr<Device> open_force_device(const std::string& kind, int index, const DeviceFrame& frame)
{
    std::unique_ptr<Device> vendor;
    if (kind == "openhaptics") {
        if (index > 0) throw InputError("--device openhaptics: one OpenHaptics device (the default one) can be used");
        vendor = std::make_unique<OpenHapticsDevice>();
    } else if (kind == "forcedimension") {
        vendor = std::make_unique<ForceDimensionDevice>(index);
    } else {
        throw InputError("--device " + kind + ": not a force-feedback device (openhaptics, forcedimension)");
    }
    return std::make_unique<FramedDevice>(std::move(vendor), frame);
}

} // namespace vox::haptics
