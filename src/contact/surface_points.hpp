#pragma once
// Points of the object's surface with their area and outward normal, world mm: what the haptic
// thread touches. The simulation thread fills one (the surface near the tool) and publishes it;
// the vectors are sized once, up front, so the haptic thread never allocates.

#include <Eigen/Core>

#include <cstddef>
#include <vector>

namespace vox::contact {

struct SurfacePoints {
    double t_s = -1e300;                      ///< simulated time the positions are from
    std::size_t count = 0;                    ///< points in use (the vectors hold capacity())
    std::vector<Eigen::Vector3d> positions_mm;
    std::vector<Eigen::Vector3d> normals;     ///< outward, unit
    std::vector<double> areas_mm2;
    bool truncated = false;                   ///< more points were near than the capacity holds

    explicit SurfacePoints(std::size_t capacity = 0)
        : positions_mm(capacity), normals(capacity), areas_mm2(capacity)
    {
    }
    [[nodiscard]] std::size_t capacity() const { return positions_mm.size(); }
};

} // namespace vox::contact
