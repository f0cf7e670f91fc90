#include "contact/swept_contact.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

namespace vox::contact {

double first_missed_contact(const PlacedShape& from, const PlacedShape& to, double margin_mm, const SurfacePoints& points,
                            std::span<double> clearance, std::span<const double> from_distance) noexcept
{
    const bool known = from_distance.size() >= points.count;
    constexpr double far = std::numeric_limits<double>::infinity();
    const bool keep = clearance.size() >= points.count;
    if (keep) std::fill_n(clearance.begin(), points.count, far);
    // The largest speed (mm per unit t) of any point of the pushing shape: translation plus
    // rotation times the shape's radius about the tool origin.
    const Eigen::AlignedBox3d local = from.shape->bounds(margin_mm);
    double radius = 0.0;
    for (int c = 0; c < 8; ++c) radius = std::max(radius, local.corner(static_cast<Eigen::AlignedBox3d::CornerType>(c)).norm());
    const double angle = from.orientation.angularDistance(to.orientation);
    const double speed = (to.position - from.position).norm() + angle * radius;
    if (!(speed > 0.0)) return 1.0; // nothing moves: nothing is reached
    Eigen::AlignedBox3d swept = from.world_bounds(margin_mm);
    swept.extend(to.world_bounds(margin_mm));
    swept.extend(swept.min() - Eigen::Vector3d::Constant(angle * radius));
    swept.extend(swept.max() + Eigen::Vector3d::Constant(angle * radius));
    auto at = [&](double t) {
        PlacedShape pose = from;
        pose.position = (1.0 - t) * from.position + t * to.position;
        pose.orientation = from.orientation.slerp(t, to.orientation);
        return pose;
    };
    // A caught point ends `grip` inside the pushing shape, so that the penalty contact has it (with
    // its stiffness) from the next step on; a point touched only at depth zero would not resist.
    const double grip = 1e-3, tolerance = 1e-4; // mm
    double first = 1.0;
    // The points near the move, leaving out those whose slack (SurfacePoints::slack_pose) exceeds
    // what the tool had spent of it at the move's start by more than the move: out of its reach.
    points.for_each_point_near(swept, [&](std::size_t i) {
        const Eigen::Vector3d& p = points.positions_mm[i];
        if (!swept.contains(p)) return;
        // The end pose's distance only for points the motion can reach at all (few, for a tick).
        const double measured = known ? from_distance[i] : far;
        const double d0 = (measured < far ? measured : from.signed_distance(p)) - margin_mm + grip;
        if (keep) clearance[i] = d0 - grip <= 0.0 ? -far : d0 - grip;
        // In the contact at the start (to within the tolerance: a point the tool leaves from a
        // micrometre deep, as a ball gliding over a surface leaves the points behind it, would
        // otherwise be found touched at t = 0 and hold the tool for ticks), or out of reach.
        if (d0 <= tolerance || d0 > speed) return;
        const double d1 = to.signed_distance(p) - margin_mm;
        if (d1 <= 0.0) return;                 // in the contact at the end: the discrete contact has it
        if (d0 + d1 + grip > speed) return;    // too far to be reached in between
        double t = d0 / speed;
        for (int step = 0; step < 64 && t < first; ++step) {
            const double d = at(t).signed_distance(p) - margin_mm + grip;
            if (d <= tolerance) {
                first = std::min(first, t);
                break;
            }
            t += d / speed;
        }
    }, points.slack_spent(from, margin_mm) + speed - grip);
    return first;
}

} // namespace vox::contact
