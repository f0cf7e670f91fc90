#pragma once
// Continuous collision for the haptic proxy: between two ticks the tool moves from one pose to
// the next, and a thin tool moving fast can pass a surface point without the point being inside
// the pushing shape at either tick (a discrete test misses it: the tool tunnels through). The
// first time such a point touches the pushing shape is found by conservative advancement on the
// exact signed distance: the distance from a point to a shape changes no faster than the shape
// moves, so stepping time by (distance - margin) / (largest speed of any point of the tool) never
// steps over a contact.

#include "contact/surface_points.hpp"
#include "contact/tool_shape.hpp"

#include <span>

namespace vox::contact {

/// The earliest time t in [0, 1] at which a point of `points` that is not in the contact at
/// either `from` or `to` comes 1 um inside the pushing shape (the tool grown by `margin_mm`) while
/// the tool moves linearly from `from` to `to` (position linear, orientation slerped); 1 when
/// there is none. Stopping there leaves the point in the penalty contact, which then holds the
/// tool. Never allocates, locks or throws.
/// `clearance`, when given (at least points.count long), receives for each point its distance
/// outside the pushing shape at `from`, mm, or -infinity when the point is in the contact there;
/// points outside the box the move sweeps are left at +infinity, unmeasured.
/// `from_distance`, when given, holds the points' signed distances at `from` already measured
/// (+infinity where not), which are then not measured again.
[[nodiscard]] double first_missed_contact(const PlacedShape& from, const PlacedShape& to, double margin_mm,
                                          const SurfacePoints& points, std::span<double> clearance = {},
                                          std::span<const double> from_distance = {}) noexcept;

} // namespace vox::contact
