#pragma once
// The scene's tools acting on a simulation, frame by frame, the same for every method. Each
// placed tool (where the script puts it, or where a device drives it) touches the surface by
// penalty contact, integrated over its move since the last frame. A cutting tool cuts only where
// its inner shape reaches the material and the contact pressure is at or above its threshold, and
// only while that holds: what decides a cut is the contact the user would feel. A two-phase tool
// (the sculpting paper's) holds the object still from its first touch while it marks its path;
// when the condition is met the whole marked path is cut at once and the object moves again,
// without further cuts until the tool lets go. A wetting tool wets what it touches. Where the
// cut goes and what it does to the object is the method's (sim/method.hpp).

#include "sim/method.hpp"

#include <vector>

namespace vox::sim {

/// The contact shape of a scene tool. Throws InputError when a mesh tool's file cannot be read.
[[nodiscard]] contact::ToolShape make_tool_shape(const io::ToolSpec& tool);

/// One tool during one frame.
struct ToolFrame {
    bool placed = false;
    Eigen::Vector3d position_mm = Eigen::Vector3d::Zero();
    Eigen::Vector3d force_n = Eigen::Vector3d::Zero();     ///< on the tool (the object's reaction)
    Eigen::Vector3d torque_n_mm = Eigen::Vector3d::Zero(); ///< on the tool, about its origin
    double pressure_pa = 0.0;
    double contact_area_mm2 = 0.0;
    bool cut = false; ///< it cut this frame
};

/// What the tools did in one frame, and how long each phase took (ms).
struct ToolsFrame {
    double collision_ms = 0.0;   ///< contact between tools and surface, and the loads handed to the solver
    double propagation_ms = 0.0; ///< finding what the cuts take (voxels, faces, tetrahedra)
    CutFigures cut;              ///< the frame's cuts, all tools together
    std::vector<ToolFrame> tools; ///< one per scene tool
    /// A two-phase tool is marking its cut: the object is held still this frame (no solver step).
    bool hold_object = false;
    /// Collision, propagation, grid update and remesh: the branched-grid paper's cutting frame.
    [[nodiscard]] double cutting_ms() const { return collision_ms + propagation_ms + cut.grid_update_ms + cut.remesh_ms; }
};

class ToolPolicy {
public:
    /// Keeps a reference to `scene`, whose tool settings may change between frames (the viewer's
    /// keys). Throws InputError when a mesh tool's file cannot be read.
    explicit ToolPolicy(const io::Scene& scene);

    /// The frame ending at simulated time `t_s` (it began at t_s - dt_s): places the tools, lets
    /// them touch, cut and wet `method`, and leaves their contact forces with it for the next step.
    ToolsFrame frame(Method& method, double t_s, double dt_s);

    /// A device moves `tool` from now on (its script entries are ignored): its pose for the next
    /// frames, world mm.
    void drive(std::size_t tool, const Eigen::Vector3d& position_mm, const Eigen::Quaterniond& orientation);
    /// The device lets go of `tool`: the script places it again (nowhere, without entries).
    void release(std::size_t tool);
    /// Forgets every tool's last pose and contact episode (after the object was restored).
    void reset();

    [[nodiscard]] const contact::ToolShape& shape(std::size_t tool) const { return m_shapes[tool]; }
    /// Where `tool` was at the last frame (its shape null when it was not placed).
    [[nodiscard]] const contact::PlacedShape& placed(std::size_t tool) const { return m_last_pose[tool]; }

private:
    const io::Scene& m_scene;
    std::vector<contact::ToolShape> m_shapes;
    std::vector<contact::PlacedShape> m_last_pose; ///< per tool, at the last frame it was placed (no shape: not placed)
    std::vector<bool> m_episode_cut;               ///< two-phase: this contact has cut its marked path
    std::vector<bool> m_driven;                    ///< a device moves the tool
    std::vector<contact::PlacedShape> m_driven_pose;
};

} // namespace vox::sim
