#pragma once
// The last stage before a force reaches a device, run in the 1 kHz loop: it never allocates,
// locks, logs or throws. In order:
//  - a non-finite force (NaN, infinity) becomes zero and is counted;
//  - the force is scaled down to the device's maximum;
//  - during the start-up interval the force ramps in linearly from zero (no jolt at power-on),
//    and again after the device comes back from a fault (the hand has moved meanwhile);
//  - when the contact snapshot the force came from is older than the stale limit (50 ms), the
//    force fades linearly to zero over the fade interval, and stays zero until a fresh snapshot.

#include "haptics/device.hpp"

#include <Eigen/Core>

#include <algorithm>
#include <cmath>
#include <cstdint>

namespace vox::haptics {

struct SafetySettings {
    double max_force_n = 3.0;   ///< the device's maximum, N
    double ramp_s = 1.0;        ///< start-up ramp
    double stale_s = 0.05;      ///< snapshot age beyond which the force fades
    double fade_s = 0.05;       ///< how long the fade takes
};

/// A device's safety settings: the defaults, clamped to its own maximum force where it declares one.
[[nodiscard]] inline SafetySettings safety_for(const DeviceLimits& limits)
{
    SafetySettings s;
    if (limits.force_output && limits.max_force_n > 0.0) s.max_force_n = limits.max_force_n;
    return s;
}

class ForceSafety {
public:
    explicit ForceSafety(const SafetySettings& s = {}) : m_s(s) {}

    /// The force to send at loop time `now_s` (s since the loop started) for a contact force
    /// computed from a snapshot `snapshot_age_s` old.
    Eigen::Vector3d filter(const Eigen::Vector3d& force, double now_s, double snapshot_age_s) noexcept
    {
        Eigen::Vector3d f = force;
        if (!f.allFinite()) {
            ++m_non_finite;
            f.setZero();
        }
        const double norm = f.norm();
        if (norm > m_s.max_force_n) {
            ++m_clamped;
            f *= m_s.max_force_n / norm;
        }
        double gain = 1.0;
        if (m_s.ramp_s > 0.0) gain = std::clamp((now_s - m_ramp_from_s) / m_s.ramp_s, 0.0, 1.0);
        if (!(snapshot_age_s <= m_s.stale_s)) { // NaN ages count as stale
            const double over = snapshot_age_s - m_s.stale_s;
            gain *= (m_s.fade_s > 0.0 && std::isfinite(over)) ? std::clamp(1.0 - over / m_s.fade_s, 0.0, 1.0) : 0.0;
        }
        return gain * f;
    }

    /// The device is faulted at `now_s`: once it answers again, the force ramps in from zero.
    void hold_off(double now_s) noexcept { m_ramp_from_s = now_s; }

    [[nodiscard]] std::uint64_t non_finite_count() const noexcept { return m_non_finite; }
    [[nodiscard]] std::uint64_t clamped_count() const noexcept { return m_clamped; }

private:
    SafetySettings m_s;
    double m_ramp_from_s = 0.0;
    std::uint64_t m_non_finite = 0, m_clamped = 0;
};

} // namespace vox::haptics
