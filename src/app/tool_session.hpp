#pragma once
// The scene's tools acting on a simulation, frame by frame: each placed tool touches the surface
// (penalty contact), cuts where its inner shape reaches material and the contact pressure exceeds
// its threshold (removing voxels or separating faces), wets what it touches, and leaves its
// contact forces with the solver for the next step. What decides a cut is the contact the user
// would feel.

#include "app/scene_simulation.hpp"
#include "contact/tool_shape.hpp"

#include <unordered_set>
#include <vector>

namespace vox::app {

/// The contact shape of a scene tool. Throws InputError when a mesh tool's file cannot be read.
contact::ToolShape make_tool_shape(const io::ToolSpec& tool);

/// One tool during one frame.
struct ToolFrame {
    bool placed = false;
    Eigen::Vector3d position_mm = Eigen::Vector3d::Zero();
    Eigen::Vector3d force_n = Eigen::Vector3d::Zero(); ///< on the tool (the object's reaction)
    Eigen::Vector3d torque_n_mm = Eigen::Vector3d::Zero(); ///< on the tool, about its origin
    double pressure_pa = 0.0;
    double contact_area_mm2 = 0.0;
    bool cut = false; ///< it cut this frame
};

/// What the tools did in one frame, and how long each phase took.
struct ToolFrameStats {
    double collision_ms = 0.0;   ///< contact between tools and surface
    double propagation_ms = 0.0; ///< finding the voxels to remove or the faces to open
    double grid_update_ms = 0.0;
    double remesh_ms = 0.0;
    double fem_update_ms = 0.0;  ///< model rebuilt and state carried over
    std::size_t removed_voxels = 0;
    std::size_t separated_faces = 0;
    std::size_t separated_voxels = 0; ///< voxels with a face opened this frame
    std::vector<ToolFrame> tools; ///< one per scene tool
    /// A two-phase tool is marking its cut: the object is held still this frame (no solver step).
    bool hold_object = false;
    [[nodiscard]] double cutting_ms() const { return collision_ms + propagation_ms + grid_update_ms + remesh_ms; }
};

/// The voxels one cut removed and the faces it opened, in the order the cuts were made: replaying
/// them on the same object rebuilds the same grid (the viewer's undo).
struct CutRecord {
    std::vector<grid::Coord> removed;
    std::vector<std::pair<grid::Coord, int>> faces;
};

class ToolSession {
public:
    /// Throws InputError when a mesh tool's file cannot be read.
    explicit ToolSession(const io::Scene& scene);

    /// Places the tools at simulated time `t_s`, lets them touch, cut and wet `sim` (built on
    /// `grid`), and sets the solver's contact forces for the next step of `dt_s`.
    ToolFrameStats frame(SceneSimulation& sim, grid::BranchedGrid& grid, double t_s, double dt_s);


    /// A device moves `tool` from now on (its script entries are ignored): its pose for the next
    /// frames, world mm.
    void drive(std::size_t tool, const Eigen::Vector3d& position_mm, const Eigen::Quaterniond& orientation);
    /// The device lets go of `tool`: the script places it again (nowhere, without entries).
    void release(std::size_t tool)
    {
        m_driven.at(tool) = false;
        m_last_pose[tool] = {};
    }

    [[nodiscard]] const contact::ToolShape& shape(std::size_t tool) const { return m_shapes[tool]; }

    /// Where `tool` was at the last frame (its shape null when it was not placed).
    [[nodiscard]] const contact::PlacedShape& placed(std::size_t tool) const { return m_last_pose[tool]; }

    /// Every cut from now on is appended to `log` (null: no record).
    void log_cuts(std::vector<CutRecord>* log) { m_cut_log = log; }

    /// Voxels that have had a face opened since the session began.
    [[nodiscard]] std::size_t separated_voxels() const { return m_separated.size(); }

private:
    const io::Scene& m_scene;
    std::vector<contact::ToolShape> m_shapes;
    /// Per tool: its cutting section at the previous frame, in rest space (separating tools only):
    /// a frame's cut opens what the section swept since.
    std::vector<std::vector<Eigen::Vector3d>> m_previous_section;
    std::unordered_set<std::uint32_t> m_separated; ///< voxel slots with an opened face
    /// Two-phase tools: the section where the marking began (rest space), and whether this
    /// contact has already cut (then the object moves again until the tool lets go).
    std::vector<std::vector<Eigen::Vector3d>> m_marked_from;
    std::vector<bool> m_episode_cut;
    std::vector<bool> m_driven;                   ///< a device moves the tool
    std::vector<contact::PlacedShape> m_driven_pose;
    std::vector<contact::PlacedShape> m_last_pose; ///< per tool, at the last frame it was placed (no shape: not placed)
    std::vector<CutRecord>* m_cut_log = nullptr;
};

} // namespace vox::app
