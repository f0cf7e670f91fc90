#pragma once
// A blade's sweep bending round the vertical for the tests: flat patches along an arc in x-y,
// through z0 to z1, each facing the arc's centre.

#include "isxfem/cut_surface.hpp"

#include <algorithm>
#include <cmath>

namespace vox::test {

/// Patches of `step` radians along the arc of `radius` about `centre`, from angle `from` to `to`,
/// the angle a at centre + radius (-cos a, sin a) (a = 0 the arc's point nearest -x).
inline isxfem::CutSurface arc_sweep(const Eigen::Vector2d& centre, double radius, double from, double to, double step, double z0 = -1.0,
                                    double z1 = 5.0)
{
    auto at = [&](double angle) { return Eigen::Vector2d(centre + radius * Eigen::Vector2d(-std::cos(angle), std::sin(angle))); };
    isxfem::CutSurface sweep;
    for (double angle = from; angle < to - 1e-12; angle += step) {
        const Eigen::Vector2d a = at(angle), b = at(std::min(angle + step, to));
        isxfem::CutPatch p;
        p.corners = {{a.x(), a.y(), z0}, {b.x(), b.y(), z0}, {b.x(), b.y(), z1}, {a.x(), a.y(), z1}};
        const Eigen::Vector2d towards_centre = (centre - 0.5 * (a + b)).normalized();
        p.normal = {towards_centre.x(), towards_centre.y(), 0.0};
        sweep.add(p); // CutSurface::add turns the corners to face the normal
    }
    return sweep;
}

} // namespace vox::test
