#pragma once
// The region of a plane that a convex profile covers as it moves and turns within the plane, frame
// by frame: what a blade's mid-plane has passed through. Each frame adds the convex hull of the
// profile placed at the frame's start and at its end: exact for a translation (the Minkowski sum
// of the profile and the segment), and for a turn within one frame the hull of the two placements,
// which differs from the swept area only by the arcs its corners trace (small for the few degrees
// a blade turns in a frame).

#include <Eigen/Core>

#include <vector>

namespace vox::contact {

class SweptProfile {
public:
    /// `profile`: a convex polygon, counter-clockwise, in the tool's own plane coordinates.
    explicit SweptProfile(std::vector<Eigen::Vector2d> profile);

    /// One frame: the profile turned by r0 and moved by t0 at its start, by r1 and t1 at its end
    /// (r0, r1 rotations of the plane).
    void add(const Eigen::Matrix2d& r0, const Eigen::Vector2d& t0, const Eigen::Matrix2d& r1, const Eigen::Vector2d& t1);
    void clear() { m_hulls.clear(); }
    [[nodiscard]] bool empty() const { return m_hulls.empty(); }
    /// Whether q lies in what the frames added so far covered.
    [[nodiscard]] bool covers(const Eigen::Vector2d& q) const;

private:
    std::vector<Eigen::Vector2d> m_profile;
    std::vector<std::vector<Eigen::Vector2d>> m_hulls; ///< per frame, counter-clockwise
};

/// The convex hull of `points`, counter-clockwise, without collinear points (Andrew's monotone
/// chain).
std::vector<Eigen::Vector2d> convex_hull(std::vector<Eigen::Vector2d> points);

} // namespace vox::contact
