#pragma once
// A tool is a proxy joined to what drives it (a script, a device, the mouse) by a coupling spring:
// the god-object of Zilles and Salisbury 1995 and the proxy of Ruspini et al. 1997, as the voxel
// bone-surgery simulators use it (Agus et al. 2003, Morris et al. 2006). The driver goes where the
// hand or the script puts it; the proxy follows it as far as the material lets it. Material the
// tool does not cut or drill stops the proxy: no surface point gets deeper into the tool's
// pushing shape than depth_bound_mm(), however hard the driver pulls, so a tool cannot be pushed
// through material thinner than itself nor forget a point its centre has passed. What the
// driver's pull does to the material is the coupling spring's force, handed to the solver as the
// penalty contact at the proxy scaled up to carry it (load_scale()).
//
// The proxy moves by Newton steps on the balance k_c (x_driver - x) + F(x) = 0 (F the penalty
// contact on the tool, contact/penalty_contact.hpp). Each step is cut short where a point would
// pass the depth bound (conservative advancement: a distance is 1-Lipschitz, so a point whose gap
// to the bound is g cannot close it while the tool moves less than g), then the rest of the step
// slides along the surface, its component into the blocking point removed (up to three blocking
// directions, as the god-object slides along up to three planes), and the continuous tool-mesh
// check (contact/tool_sweep.hpp) stops what passes between points. The haptic loop takes one step a
// tick (haptics/coupled_tool.hpp); a script-driven tool settles within the frame (settle()).
// move() and step() never allocate, lock, log or throw.

#include "contact/penalty_contact.hpp"
#include "contact/surface_points.hpp"
#include "contact/tool_sweep.hpp"

#include <Eigen/Core>

#include <cstdint>
#include <span>
#include <vector>

namespace vox::contact {

/// How deep the pushing shape of `shape` (grown by `margin_mm`) may be held in material it does
/// not cut, mm: 0.5 mm, or the margin plus 0.02 mm if that is more (the inner shape reaches the
/// surface by that much, as a cut or drill needs), but at most 90 % of the pushing shape's
/// half-thickness at the tool's origin, so that no point can pass its middle.
[[nodiscard]] double depth_bound_mm(const ToolShape& shape, double margin_mm) noexcept;

/// The deepest any surface point lies inside the pushing shape of `tool` (grown by `margin_mm`),
/// mm; 0 without contact. Points the contact patch replaces are left out.
[[nodiscard]] double deepest_point_mm(const PlacedShape& tool, double margin_mm, const SurfacePoints& points) noexcept;

/// How much the penalty contact at the proxy is scaled to carry the driver's pull: the coupling
/// force's push against the contact over the contact's own force, or, where the material has come
/// deeper into the tool than the bound (it was pushed in), the depth over the bound; at least 1.
/// `coupling_n`: the spring's force on the proxy, k_c (x_driver - x_proxy); `contact_n`: the
/// contact's force on the tool there; `deepest_mm`: deepest_point_mm() there.
[[nodiscard]] double load_scale(const Eigen::Vector3d& coupling_n, const Eigen::Vector3d& contact_n, double deepest_mm, double bound_mm) noexcept;

class ProxyMover {
public:
    /// `point_capacity`: the capacity() of the largest SurfacePoints it will be given.
    ProxyMover(const ToolShape& shape, const ContactParameters& contact, std::size_t point_capacity);

    /// Moves `proxy` by up to `step` (world mm, no turn) against `points`, sliding along what
    /// blocks it; returns the move made. `distance`: the points' signed distances at the proxy
    /// already measured (penalty_totals), +infinity where not; may be empty.
    Eigen::Vector3d move(PlacedShape& proxy, const Eigen::Vector3d& step, const SurfacePoints& points,
                         std::span<const double> distance = {}) noexcept;

    /// One Newton step of the proxy toward `driver` through a spring of `coupling_n_per_mm`,
    /// against `contact` (the penalty totals at the proxy), then move(). In contact the step is
    /// at most the margin long (the linearised contact holds only over the depths it was taken
    /// at). Returns the move made.
    Eigen::Vector3d step(PlacedShape& proxy, const Eigen::Vector3d& driver, double coupling_n_per_mm, const ContactTotals& contact,
                         const SurfacePoints& points, std::span<const double> distance = {}) noexcept;

    /// Newton steps until the proxy rests (a move under 1 um) or `iterations` are spent; returns
    /// the contact at the proxy where it rests (with pressure).
    ContactTotals settle(PlacedShape& proxy, const Eigen::Vector3d& driver, double coupling_n_per_mm, const SurfacePoints& points,
                         int iterations = 32);

    [[nodiscard]] double bound_mm() const { return m_bound; }
    [[nodiscard]] const ContactParameters& contact() const { return m_contact; }
    /// Whether the last move() was stopped short by the depth bound or the mesh check.
    [[nodiscard]] bool blocked() const { return m_blocked; }
    /// The continuous tool-mesh check of the last move.
    [[nodiscard]] const ToolSweep& sweep() const { return m_sweep; }

private:
    /// The share of `step` the proxy can go before a point passes its depth bound (1: all of it);
    /// `blocking` receives the direction in which that point's depth grows fastest. `distance`:
    /// the points' distances at `proxy` where measured (+infinity where not), or empty.
    double bounded_share(const PlacedShape& proxy, const Eigen::Vector3d& step, const SurfacePoints& points, std::span<const double> distance,
                         Eigen::Vector3d& blocking) noexcept;

    ContactParameters m_contact;
    double m_bound;
    ToolSweep m_sweep;
    std::vector<std::uint32_t> m_candidates; ///< points that may reach their bound during a move
    std::vector<double> m_limit;             ///< their bound: max(bound, depth at the start)
    std::vector<double> m_distance;          ///< settle(): the points' distances at the proxy
    bool m_blocked = false;
};

} // namespace vox::contact
