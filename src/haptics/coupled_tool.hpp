#pragma once
// Virtual coupling between the device and the tool in the simulation (the proxy): a spring-damper
// pulls the proxy toward the device; the contact with the surface snapshot holds it back. The
// proxy is massless and found each tick implicitly against the linearised contact,
//     (k_c I + K) dx = k_c (x_device - x) + F_contact(x),
// K the contact's stiffness, so stiff contact and a stiff coupling stay stable at 1 kHz (Colgate
// et al.'s virtual coupling; the adaptive shape matching paper couples the same way). The user
// feels the spring's force, k_c (x_proxy - x_device) plus damping, which the loop's safety stage
// then clamps. The step is the one every tool's proxy takes (contact/proxy.hpp): no surface point
// gets deeper into the pushing shape than its bound however hard the device pulls, the step
// slides along what blocks it, and the tool's triangle mesh is swept against the snapshot's
// triangles for features thinner than the gaps between surface points (contact/tool_sweep.hpp), so
// a fast, thin tool cannot tunnel through the surface between ticks. While the simulation says the
// tool cuts through what it touches (set_passing), the proxy goes where the device is and the user
// feels the contact there. A new snapshot moves the surface under
// the proxy at once (the simulation stepped): what the user feels follows the proxy's move over as
// many ticks as the snapshots come apart, not in one, so the force does not jump once a frame.
// Where the snapshot carries a subdivided patch at the contact (contact/contact_patch.hpp), the
// proxy presses the patch's spring layer there instead of the snapshot's rigid points, so the
// surface gives under the tool between frames as the FEM would.
// The contact at the proxy does not depend on the device's new state: the loop measures it after
// the tick's forces are sent (prepare(), in the rest of the millisecond), for the next tick, which
// then reads the device and answers with the proxy's step, the continuous check and the spring
// alone. The work per tick is the same; what the user waits for between reading the device and
// feeling the force is not the contact's. The proxy takes the device's orientation of the tick
// before (1 ms later than its position): a turn is not felt as a force.
// Everything here runs in the 1 kHz loop: no allocation, lock, log or throw.

#include "contact/contact_patch.hpp"
#include "contact/penalty_contact.hpp"
#include "contact/proxy.hpp"
#include "haptics/device.hpp"

#include <atomic>
#include <vector>

namespace vox::haptics {

struct CouplingSettings {
    double stiffness_n_per_mm = 0.5;   ///< the spring between device and proxy
    double damping_n_s_per_mm = 0.002; ///< on their relative velocity
};

class CoupledTool {
public:
    /// `snapshot_capacity`: the capacity() of the surface snapshots update() will be given.
    CoupledTool(const contact::ToolShape& shape, const contact::ContactParameters& contact, const CouplingSettings& coupling,
                std::size_t snapshot_capacity);

    /// One tick of `dt_s`: moves the proxy for the device's new state against `surface` and
    /// returns the force for the device, N. The first call puts the proxy at the device.
    Eigen::Vector3d update(const DeviceState& device, const contact::SurfacePoints& surface, double dt_s) noexcept;
    /// After the tick's forces are sent: the contact of the proxy, turned to `device`'s
    /// orientation, with `surface` (the newest snapshot), which the next update() on that same
    /// snapshot starts from instead of measuring it then. Before the first update(): nothing.
    void prepare(const DeviceState& device, const contact::SurfacePoints& surface, double dt_s) noexcept;

    /// The proxy: where the tool is in the simulation.
    [[nodiscard]] const contact::PlacedShape& proxy() const { return m_proxy; }
    /// Where the simulation is to put the tool: the proxy, backed out of a contact patch by how
    /// far its layer gives (the FEM takes up the layer's give itself, from the load the user
    /// feels; contact/contact_patch.hpp). Without a patch, the proxy.
    [[nodiscard]] contact::PlacedShape handed_pose() const;
    /// A new snapshot's move is spread over at most this many ticks (the safety stage fades the
    /// force of a snapshot 50 ms old).
    static constexpr int k_max_spread_ticks = 50;
    /// Where the user feels it: the proxy, plus what is left of a new snapshot's move to spread.
    [[nodiscard]] Eigen::Vector3d felt_position() const { return m_proxy.position + m_spread; }
    /// The continuous check of the last update (whether it swept the tool's mesh, and stopped on it).
    [[nodiscard]] const contact::ToolSweep& sweep() const { return m_mover.sweep(); }
    /// The simulation cuts through what the tool touches (sim::ToolPolicy::passing): from the next
    /// tick the proxy is not held by the material. Safe to call from another thread.
    void set_passing(bool passing) noexcept { m_passing.store(passing, std::memory_order_relaxed); }
    /// The device's position at the last update: the driver, world mm.
    [[nodiscard]] const Eigen::Vector3d& driver() const { return m_previous_device; }
    [[nodiscard]] double coupling_stiffness_n_per_mm() const { return m_coupling.stiffness_n_per_mm; }
    /// Whether the last update started from the contact prepare() measured (else it measured it).
    [[nodiscard]] bool used_prepared() const { return m_used_prepared; }
    /// The contact at the proxy before the last update's step (force and stiffness; no pressure).
    [[nodiscard]] const contact::ContactTotals& contact() const { return m_contact; }
    /// The contact patch's layer as the last update left it, and how long it took to step, us.
    [[nodiscard]] const contact::ContactPatchState& patch() const { return m_patch; }
    [[nodiscard]] double patch_us() const { return m_patch_us; }

private:
    /// The contact (and the patch's step) at the proxy where it is now: m_contact, m_distance.
    void measure_contact(const contact::SurfacePoints& surface, double dt_s) noexcept;

    contact::ContactParameters m_parameters;
    CouplingSettings m_coupling;
    contact::PlacedShape m_proxy;
    contact::ContactTotals m_contact;
    contact::ProxyMover m_mover;
    std::atomic<bool> m_passing{false};
    std::vector<double> m_distance; ///< per snapshot point, this tick's distance at the proxy
    contact::ContactPatchState m_patch;
    double m_patch_us = 0.0;
    Eigen::Vector3d m_patch_force = Eigen::Vector3d::Zero(); ///< the patch's part of m_contact
    Eigen::Vector3d m_previous_device = Eigen::Vector3d::Zero(), m_previous_felt = Eigen::Vector3d::Zero();
    /// A new snapshot's move of the proxy not felt yet, and how much of it goes each tick.
    Eigen::Vector3d m_spread = Eigen::Vector3d::Zero(), m_spread_step = Eigen::Vector3d::Zero();
    double m_snapshot_t_s = 0.0;  ///< the snapshot of the last update
    int m_ticks_on_snapshot = 0;  ///< updates since the snapshot changed
    int m_spread_ticks = 1;       ///< updates between the last two snapshots: the move's spread
    bool m_started = false;
    /// The snapshot prepare() measured the contact on (its time), or none.
    const contact::SurfacePoints* m_prepared_on = nullptr;
    double m_prepared_t_s = 0.0;
    bool m_used_prepared = false;
};

} // namespace vox::haptics
