#pragma once
// Blades and scalpels cutting an Is-XFEM simulation along their mid-plane (the tool's x-z plane).
// While the plane stays put a stroke is one cut, and the region it covers is the union of the
// tool's profile swept frame by frame, so a tetrahedron the blade crosses whole only over several
// frames is cut once it has been.

#include "app/isxfem_simulation.hpp"
#include "io/tool_script.hpp"

#include <Eigen/Core>

#include <utility>
#include <vector>

namespace vox::app {

class BladeStroke {
public:
    explicit BladeStroke(const io::ToolSpec& tool);

    /// The blade moved from `from` to `to` over a frame; cuts where it has passed. Starts a new cut
    /// when its plane moved or turned.
    isxfem::CutReport advance(IsxfemSimulation& sim, const io::ToolPose& from, const io::ToolPose& to);

private:
    /// Whether q (stroke plane coordinates, mm) lies in the profile moved along any segment.
    [[nodiscard]] bool covered(const Eigen::Vector2d& q) const;

    std::vector<Eigen::Vector2d> m_profile; ///< mm, tool x-z
    int m_cut = -1;
    Eigen::Matrix3d m_rotation = Eigen::Matrix3d::Identity();
    Eigen::Vector3d m_origin_mm = Eigen::Vector3d::Zero();
    std::vector<std::pair<Eigen::Vector2d, Eigen::Vector2d>> m_segments;
};

/// Every placed tool of `scene` cuts for frame f (from (f - 1) dt to f dt); the frame's totals.
isxfem::CutReport cut_frame(const io::Scene& scene, IsxfemSimulation& sim, std::vector<BladeStroke>& strokes, int frame, double dt);

/// Refuses, with the scene's message, tools Is-XFEM cannot simulate yet (pushing, wetting,
/// two-phase).
void check_isxfem_tools(const io::Scene& scene);

} // namespace vox::app
