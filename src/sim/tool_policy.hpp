#pragma once
// The scene's tools acting on a simulation, frame by frame, the same for every method. Each
// placed tool is a proxy joined by a coupling spring to its driver, where the script or a device
// puts it (contact/proxy.hpp): material the tool does not cut or drill holds the proxy at its
// surface, and the penalty contact at the proxy, integrated over its move since the last frame, is
// scaled to carry the spring's pull (a script pulls as hard as it likes: the material deforms or
// holds, the tool does not pass through). A device's proxy moves in the 1 kHz loop
// (haptics/coupled_tool.hpp), a script's here, by the same steps. A cutting tool held at the
// surface that breaks in goes to its driver and cuts; from then until it leaves the material (a
// cut episode) it goes where its driver is, cutting wherever its pressure breaks in. A cutting tool cuts only where
// its inner shape reaches the material and the contact pressure is at or above its threshold, and
// only while that holds: what decides a cut is the contact the user would feel. A two-phase tool
// (the sculpting paper's) holds the object still from its first touch while it marks its path;
// when the condition is met the whole marked path is cut at once and the object moves again,
// without further cuts until the tool lets go. A wetting tool wets what it touches. Where the
// cut goes and what it does to the object is the method's (sim/method.hpp).

#include "sim/method.hpp"
#include "contact/proxy.hpp"

#include <memory>
#include <vector>

namespace vox::sim {

/// The contact shape of a scene tool. Throws InputError when a mesh tool's file cannot be read.
[[nodiscard]] contact::ToolShape make_tool_shape(const io::ToolSpec& tool);

/// One tool during one frame.
struct ToolFrame {
    bool placed = false;
    Eigen::Vector3d position_mm = Eigen::Vector3d::Zero(); ///< the tool: its proxy
    Eigen::Vector3d driver_mm = Eigen::Vector3d::Zero();   ///< where the script or device puts it
    Eigen::Vector3d coupling_force_n = Eigen::Vector3d::Zero(); ///< the spring's pull on the proxy, k_c (driver - proxy)
    double load_scale = 1.0; ///< the penalty at the proxy scaled by this to carry the pull (contact::load_scale)
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

    /// A device moves `tool` from now on (its script entries are ignored): its proxy's pose for
    /// the next frames, world mm, the device's own position (the driver) and the spring between them.
    void drive(std::size_t tool, const Eigen::Vector3d& position_mm, const Eigen::Quaterniond& orientation, const Eigen::Vector3d& driver_mm,
               double coupling_n_per_mm);
    /// `tool` is in a cut episode (it has cut since it last touched nothing): it passes through
    /// what it touches (a device's proxy follows the device) until it leaves the material.
    [[nodiscard]] bool passing(std::size_t tool) const { return m_passing[tool]; }
    /// The device lets go of `tool`: the script places it again (nowhere, without entries).
    void release(std::size_t tool);
    /// Whether `tool` does what its action says (cut, drill, wet) or only pushes: a force-feedback
    /// device's second button switches the action on while it is held. On unless a device says.
    void arm(std::size_t tool, bool on) { m_armed.at(tool) = on; }
    [[nodiscard]] bool armed(std::size_t tool) const { return m_armed[tool]; }
    /// Forgets every tool's last pose and contact episode (after the object was restored).
    void reset();

    [[nodiscard]] const contact::ToolShape& shape(std::size_t tool) const { return m_shapes[tool]; }
    /// Where `tool` was at the last frame (its shape null when it was not placed).
    [[nodiscard]] const contact::PlacedShape& placed(std::size_t tool) const { return m_last_pose[tool]; }

private:
    contact::ProxyMover& mover(std::size_t tool, const io::ToolSpec& spec);
    /// A tool held at the surface: how much its contact is scaled to carry its driver's pull, and
    /// whether, so pressed, it breaks in (its inner shape reaches the material at the cut pressure).
    struct Held {
        double load_scale = 1.0;
        bool breaks_in = false;
    };
    /// Holds `proxy` (the tool where it is, turned as its driver) at the surface of what the tool
    /// does not cut: a script's proxy settles toward its driver from where it was (`moved_on`);
    /// a device's stays where the haptic loop put it. Measured on the surface near it, sampled.
    Held hold(std::size_t tool, Method& method, const io::ToolSpec& spec, contact::PlacedShape& proxy, const Eigen::Vector3d& driver,
                double coupling_n_per_mm, bool moved_on);

    const io::Scene& m_scene;
    std::vector<contact::ToolShape> m_shapes;
    std::vector<contact::PlacedShape> m_last_pose; ///< per tool, at the last frame it was placed (no shape: not placed)
    std::vector<bool> m_episode_cut;               ///< two-phase: this contact has cut its marked path
    std::vector<bool> m_driven;                    ///< a device moves the tool
    std::vector<contact::PlacedShape> m_driven_pose;
    std::vector<Eigen::Vector3d> m_driven_driver;  ///< the device's position
    std::vector<double> m_driven_coupling;         ///< its spring, N/mm
    std::vector<bool> m_passing;                   ///< the tool is in a cut episode
    std::vector<bool> m_armed;                     ///< its action is on (else it pushes)
    /// Per tool: its proxy's steps and the surface near it, sampled each frame.
    std::vector<std::unique_ptr<contact::ProxyMover>> m_movers;
    std::vector<contact::SurfacePoints> m_near;
};

} // namespace vox::sim
