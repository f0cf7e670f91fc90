#pragma once
// Blades and scalpels cutting an Is-XFEM simulation along their mid-plane (the tool's x-z plane).
// While the plane stays put a stroke is one cut, and the region it covers is the tool's profile
// swept frame by frame as it moves and turns within the plane (contact/swept_profile.hpp), so a
// tetrahedron the blade crosses whole only over several frames is cut once it has been.

#include "app/isxfem_simulation.hpp"
#include "contact/swept_profile.hpp"
#include "io/tool_script.hpp"

#include <Eigen/Core>

#include <vector>

namespace vox::app {

class BladeStroke {
public:
    explicit BladeStroke(const io::ToolSpec& tool);

    /// The blade moved from `from` to `to` over a frame; cuts where it has passed. Starts a new cut
    /// when its plane moved or tilted (turning within the plane goes on with the stroke).
    isxfem::CutReport advance(IsxfemSimulation& sim, const io::ToolPose& from, const io::ToolPose& to);

private:
    contact::SweptProfile m_swept; ///< in the stroke's plane coordinates, mm
    int m_cut = -1;
    Eigen::Matrix3d m_rotation = Eigen::Matrix3d::Identity(); ///< the stroke's frame: its first pose
    Eigen::Vector3d m_origin_mm = Eigen::Vector3d::Zero();
};

} // namespace vox::app
