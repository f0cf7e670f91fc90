#pragma once
// The scene's tools acting on an Is-XFEM simulation, frame by frame. Every tool presses on the
// deformed, closed surface with the penalty contact of the branched-grid runs
// (contact/penalty_contact.hpp, integrated over the tool's move), and its forces are the solver's
// point loads for the next step. Blades and scalpels also cut along their mid-plane
// (app/blade_stroke.hpp): a stroke breaks in when the blade's inner shape reaches the surface with
// the contact pressure at or above the tool's cut_pressure_pa, as a branched-grid cut begins, and
// from then on cuts wherever the blade passes until it lets go (leaves the surface's reach) or
// starts a new stroke (turned or moved off its plane: app/blade_stroke.hpp). Crack walls closer together than a blade's thickness are not in its contact
// surface (they would close on it from both sides at once; walls that have opened are touched
// like the rest), so past the break-in the pressure at the blade's edge inside the material is not
// measured.
//
// Two-phase tools (the sculpting paper's section 5): from the first touch the object is held still
// (no solver step) while the blade marks its path, so it cannot slip away from the blade before
// the pressure reaches the threshold; then the whole marked path is cut at once, the object moves
// again, and the blade goes on cutting where it passes until it lets go, as a one-phase stroke.
// (The branched-grid runs stop cutting after the marked path; a blade marking a few tenths of a
// millimetre would cut no tetrahedron whole.)
//
// Not yet: wetting tools.

#include "app/blade_stroke.hpp"
#include "app/isxfem_simulation.hpp"
#include "app/tool_session.hpp"

#include <optional>
#include <vector>

namespace vox::app {

struct IsxfemToolFrame {
    isxfem::CutReport cut;        ///< the frame's cuts, all tools together
    std::vector<ToolFrame> tools; ///< one per scene tool
    bool hold_object = false;     ///< a two-phase tool is marking: no solver step this frame
};

class IsxfemTools {
public:
    /// Refuses (the scene's InputError) tools Is-XFEM cannot simulate yet; throws InputError when a
    /// mesh tool's file cannot be read.
    explicit IsxfemTools(const io::Scene& scene);

    /// Frame f, from (f - 1) dt to f dt: cuts, then sets the solver's point loads.
    IsxfemToolFrame frame(IsxfemSimulation& sim, int frame, double dt);
    /// A device moves `tool` from now on (its script entries are ignored): its pose for the next
    /// frames, world mm.
    void drive(std::size_t tool, const Eigen::Vector3d& position_mm, const Eigen::Quaterniond& orientation);
    /// Where `tool` was at the last frame (its shape null when it was not placed).
    [[nodiscard]] const contact::PlacedShape& placed(std::size_t tool) const { return m_last_pose[tool]; }

private:
    const io::Scene& m_scene;
    std::vector<contact::ToolShape> m_shapes;
    std::vector<std::optional<BladeStroke>> m_strokes; ///< per tool: blades and scalpels only
    std::vector<contact::PlacedShape> m_last_pose;      ///< per tool, at the last frame it was placed
    /// Per tool: its stroke has broken in (one phase), or its marking has cut (two phases), since
    /// it last touched.
    std::vector<bool> m_done;
    std::vector<std::optional<io::ToolPose>> m_driven; ///< per tool: the device's pose, when a device moves it
};

/// Refuses, with the scene's message, tools Is-XFEM cannot simulate yet (wetting, cutting with
/// other shapes than blades and scalpels).
void check_isxfem_tools(const io::Scene& scene);

} // namespace vox::app
