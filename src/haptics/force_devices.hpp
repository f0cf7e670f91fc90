#pragma once
// The force-feedback devices a session can open by name, through their vendors' libraries:
// "openhaptics" (3D Systems, the default device) and "forcedimension" (Force Dimension, by
// index). Each is seen in the scene through its frame, its first button a clutch
// (haptics/framed_device.hpp); its second button switches the tool's action on while held.

#include "haptics/framed_device.hpp"

#include <memory>
#include <string>

namespace vox::haptics {

/// The button that switches a force-feedback device's tool action on while held.
inline constexpr std::uint32_t k_action_button = 2u;

/// Whether `kind` names a force-feedback backend ("openhaptics", "forcedimension").
[[nodiscard]] bool is_force_device(const std::string& kind);

/// Opens device `index` of backend `kind` (OpenHaptics has one: 0) seen through `frame`. Throws
/// InputError naming the library or the device and the vendor's error.
[[nodiscard]] std::unique_ptr<Device> open_force_device(const std::string& kind, int index, const DeviceFrame& frame);

} // namespace vox::haptics
