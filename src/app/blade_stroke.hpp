#pragma once
// Blades and scalpels cutting an Is-XFEM simulation along their mid-plane (the tool's x-z plane).
// While the plane stays put (within 5 degrees and 1 mm of where the stroke began: a hand wavers) a
// stroke is one cut, and the region it covers is the tool's profile
// swept frame by frame as it moves and turns within the plane (contact/swept_profile.hpp), so a
// tetrahedron the blade crosses whole only over several frames is cut once it has been. The caller
// says which frames count (from the break-in, or from the first touch when the tool marks its cut
// in two phases) and when to cut what they swept (app/isxfem_tools.hpp).

#include "app/isxfem_simulation.hpp"
#include "contact/swept_profile.hpp"
#include "io/tool_script.hpp"

#include <Eigen/Core>

#include <vector>

namespace vox::app {

class BladeStroke {
public:
    explicit BladeStroke(const io::ToolSpec& tool);

    /// The blade moved from `from` to `to` (world) over a frame: adds the frame's sweep to the
    /// stroke's, carried back to rest space by `moved_mm` (the mean displacement of the material
    /// around the blade), and with `cut` cuts where the stroke has swept. A new stroke starts when
    /// the plane moved or tilted in the world past the tolerance (turning within the plane goes on
    /// with the stroke) or after end().
    isxfem::CutReport advance(IsxfemSimulation& sim, const io::ToolPose& from, const io::ToolPose& to, const Eigen::Vector3d& moved_mm,
                              bool cut);
    /// The blade left: the next frame starts a new stroke.
    void end() { m_swept.clear(); }

private:
    contact::SweptProfile m_swept; ///< in the stroke's rest-space plane coordinates, mm
    int m_cut = -1;
    Eigen::Matrix3d m_rotation = Eigen::Matrix3d::Identity(); ///< the stroke's frame: its first pose
    Eigen::Vector3d m_world_origin_mm = Eigen::Vector3d::Zero(); ///< where the stroke began, world
    Eigen::Vector3d m_origin_mm = Eigen::Vector3d::Zero();       ///< the cut plane's point, rest space
};

} // namespace vox::app
