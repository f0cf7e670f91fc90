#pragma once
// Blades and scalpels cutting an Is-XFEM simulation along the surface their edges sweep. Each frame
// adds a flat patch to the stroke's swept surface (isxfem/cut_surface.hpp): the convex hull of the
// blade's profile where the frame began and where it ended, carried back to rest space by the mean
// displacement of the material around the blade (only within the cut plane, once the stroke is
// going) and laid into the plane the edge sweeps: the blade's own plane when it moves along it,
// the plane holding its edge and the way it moves when it is held at a slant. A stroke is one cut,
// one crack, while the blade goes on along that plane: it may turn and tilt as it goes (a curved
// incision, however far it comes round) by up to 10 degrees a frame, and waver across the plane by
// up to 1 mm in all (that motion dropped, so the crack does not step sideways); past that a new
// stroke, a new cut, begins. A tetrahedron the blade crosses whole only over several frames is cut
// once it has been. The caller says what each frame's patch is for
// (cut now, marked for a two-phase cut, or only carrying the stroke on: sim/isxfem_method.cpp, as
// the tool policy decides).

#include "sim/isxfem_simulation.hpp"
#include "io/tool_script.hpp"
#include "isxfem/cut_surface.hpp"

#include <Eigen/Core>

#include <vector>

namespace vox::sim {

class BladeStroke {
public:
    explicit BladeStroke(const io::ToolSpec& tool);

    /// What a frame's patch is for: cut now, with every patch marked and not yet cut; kept for a
    /// later cut (two-phase marking); or only carrying the stroke on (the pressure did not hold:
    /// it is never cut, but the stroke goes on through it, one crack).
    enum class Sweep { cut, mark, pass };

    /// The blade moved from `from` to `to` (world) over a frame: adds the frame's patch to the
    /// stroke's surface, carried back to rest space by `moved_mm` (the mean displacement of the
    /// material around the blade), and cuts as `sweep` says. A new stroke starts when the blade
    /// turned or moved off its plane past the limits, or after end().
    isxfem::CutReport advance(IsxfemSimulation& sim, const io::ToolPose& from, const io::ToolPose& to, const Eigen::Vector3d& moved_mm,
                              Sweep sweep);
    /// The blade left: the next frame starts a new stroke.
    void end() { m_surface = {}; }


private:
    std::vector<Eigen::Vector2d> m_profile; ///< the blade's, in its x-z plane, mm
    isxfem::CutSurface m_surface;           ///< the stroke's, rest space, m
    std::size_t m_offered = 0;              ///< patches the model has been asked to cut with
    int m_cut = -1;
    Eigen::Vector3d m_last_normal = Eigen::Vector3d::UnitY(); ///< the blade's plane where the last frame ended, world
    Eigen::Vector3d m_last_position_mm = Eigen::Vector3d::Zero(); ///< where the last frame ended, world
    Eigen::Vector3d m_last_rest_mm = Eigen::Vector3d::Zero();     ///< and in rest space
    Eigen::Vector3d m_last_moved_mm = Eigen::Vector3d::Zero();    ///< the material's displacement there
    double m_drift_mm = 0.0; ///< how far the blade has moved across its plane since the stroke began (dropped from the sweep)
};

} // namespace vox::sim
