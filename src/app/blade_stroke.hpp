#pragma once
// Blades and scalpels cutting an Is-XFEM simulation along their mid-plane (the tool's x-z plane).
// While the plane stays put a stroke is one cut, and the region it covers is the tool's profile
// swept frame by frame as it moves and turns within the plane (contact/swept_profile.hpp), so a
// tetrahedron the blade crosses whole only over several frames is cut once it has been. A stroke
// cuts from the frame its blade breaks in (the caller says when: the contact pressure reaching the
// tool's threshold) until it ends; what it swept before does not count.

#include "app/isxfem_simulation.hpp"
#include "contact/swept_profile.hpp"
#include "io/tool_script.hpp"

#include <Eigen/Core>

#include <vector>

namespace vox::app {

class BladeStroke {
public:
    explicit BladeStroke(const io::ToolSpec& tool);

    /// The blade moved from `from` to `to` (world) over a frame; once `breaks_in` has been true in
    /// this stroke, cuts where it has passed since, carried back to rest space by `moved_mm` (the
    /// mean displacement of the material around the blade). A new stroke starts when the plane
    /// moved or tilted in the world (turning within the plane goes on with the stroke) or after
    /// end().
    isxfem::CutReport advance(IsxfemSimulation& sim, const io::ToolPose& from, const io::ToolPose& to, bool breaks_in,
                              const Eigen::Vector3d& moved_mm);
    /// The blade left: the next frame starts a new stroke.
    void end() { m_swept.clear(); m_started = false; m_cutting = false; }
    /// Whether this stroke has broken in and cuts.
    [[nodiscard]] bool cutting() const { return m_cutting; }

private:
    contact::SweptProfile m_swept; ///< in the stroke's plane coordinates, mm, since it broke in
    bool m_started = false, m_cutting = false;
    int m_cut = -1;
    Eigen::Matrix3d m_rotation = Eigen::Matrix3d::Identity(); ///< the stroke's frame: its first pose
    Eigen::Vector3d m_world_origin_mm = Eigen::Vector3d::Zero(); ///< where the stroke began, world
    Eigen::Vector3d m_origin_mm = Eigen::Vector3d::Zero();       ///< the cut plane's point, rest space
};

} // namespace vox::app
