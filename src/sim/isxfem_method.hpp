#pragma once
// Is-XFEM (`"solver": {"type": "isxfem"}`) behind the method interface: the tetrahedra of the
// scene's object at its level (sim/isxfem_simulation.hpp), tools pressing on its closed surface
// (point loads at the material points they touch), and blades and scalpels cutting along the
// surface their strokes sweep (sim/blade_stroke.hpp), without remeshing.
//
// Refused by name, with the reason in docs/isxfem.md: removing material (`"cut_mode": "remove"`),
// wetting, cutting with other shapes than blades and scalpels, loads, plasticity, the static mode,
// "levels": "auto" and the multigrid preconditioner.

#include "sim/blade_stroke.hpp"
#include "sim/isxfem_simulation.hpp"
#include "sim/obstacles.hpp"
#include "sim/method.hpp"

#include <memory>
#include <optional>
#include <set>
#include <vector>

namespace vox::sim {

/// Refuses, with the scene's message naming the key, what Is-XFEM cannot simulate (above).
void check_isxfem_scene(const io::Scene& scene);

class IsxfemMethod final : public Method {
public:
    /// Throws the scene's InputError for what Is-XFEM cannot simulate, or when a constraint box
    /// holds no voxel centre.
    IsxfemMethod(const io::Scene& scene, std::shared_ptr<const grid::LabelGrid> labels, int level);
    ~IsxfemMethod() override;

    [[nodiscard]] const char* name() const override { return "isxfem"; }
    [[nodiscard]] int level() const override { return m_level; }
    [[nodiscard]] std::size_t element_count() const override { return m_sim->tet_count(); }
    [[nodiscard]] std::size_t dof_count() const override { return m_sim->solver().dof_count(); }
    [[nodiscard]] std::string linear_solver() const override;
    [[nodiscard]] std::string description() const override;

    void begin_tools(std::size_t tool_count) override;
    const contact::ContactResult& touch(std::size_t tool, const io::ToolSpec& spec, const contact::PlacedShape& at,
                                        const contact::PlacedShape* from) override;
    CutFigures follow(std::size_t tool, const io::ToolSpec& spec, const io::ToolPose& from, const contact::PlacedShape& at,
                      const CutOrder& order) override;
    void lift(std::size_t tool) override;
    void wet(std::size_t tool, double water) override;
    /// Never called: check_isxfem_scene refuses drilling tools (Is-XFEM does not remove material).
    CutFigures drill(std::size_t, const io::ToolSpec&, const contact::PlacedShape&, double) override { return {}; }
    void end_tools() override;
    StepFigures step() override;

    [[nodiscard]] surface::SurfaceMesh surface_mesh() const override { return m_sim->surface_mesh(); }
    /// Is-XFEM's cuts separate material and remove none: the voxels it was built from.
    [[nodiscard]] grid::LabelGrid rest_voxels() const override { return m_labels->clone(); }
    [[nodiscard]] std::optional<io::VtuMesh> fem_mesh() const override;
    [[nodiscard]] std::vector<SurfaceMark> surface_marks() const override;
    [[nodiscard]] std::vector<float> surface_wetness() const override;
    [[nodiscard]] std::vector<Eigen::Vector3d> surface_displacements_mm() const override;
    [[nodiscard]] std::vector<std::uint64_t> surface_keys() const override { return m_sim->surface_keys(); }
    void sample_surface(const Eigen::AlignedBox3d& box, const io::ToolSpec& tool, contact::SurfacePoints& out) const override;
    [[nodiscard]] std::size_t piece_count() const override;
    [[nodiscard]] const std::vector<contact::Obstacle>& obstacles() const override { return m_obstacles; }
    [[nodiscard]] Eigen::Vector3d obstacle_force_n() const override { return m_obstacle_force; }
    [[nodiscard]] PieceContactFigures piece_contact() const override { return m_piece_contact; }
    void add_frame_figures(nlohmann::json& frame) const override;
    void add_summary_figures(nlohmann::json& summary) const override;

    [[nodiscard]] std::unique_ptr<Method> at_level(int level) const override;
    [[nodiscard]] std::size_t cut_count() const override;
    [[nodiscard]] nlohmann::json cuts_since(std::size_t from) const override;
    void replay_cuts(const nlohmann::json& cuts) override;
    [[nodiscard]] std::vector<double> motion() const override;
    void set_motion(const std::vector<double>& numbers) override;
    [[nodiscard]] std::unique_ptr<Checkpoint> checkpoint() const override;
    void restore(const Checkpoint& checkpoint) override;

    [[nodiscard]] IsxfemSimulation& simulation() { return *m_sim; }
    [[nodiscard]] const IsxfemSimulation& simulation() const { return *m_sim; }

private:
    io::Scene m_scene;
    std::shared_ptr<const grid::LabelGrid> m_labels;
    int m_level = 1;
    std::unique_ptr<grid::BranchedGrid> m_grid;
    std::unique_ptr<IsxfemSimulation> m_sim;
    std::vector<contact::Obstacle> m_obstacles;
    std::vector<contact::FrictionAnchors> m_anchors; ///< per obstacle
    std::size_t m_obstacle_pairs = 0;                ///< the solver's first pair contacts are the obstacles' pushes
    Eigen::Vector3d m_obstacle_force = Eigen::Vector3d::Zero(); ///< on the object, this frame
    PieceContactFigures m_piece_contact;                        ///< this frame
    // Per tool.
    std::vector<std::optional<BladeStroke>> m_strokes; ///< blades and scalpels that cut
    std::vector<contact::ContactResult> m_contact;
    // This frame.
    std::vector<isxfem::PointLoad> m_loads;
    std::vector<std::size_t> m_cuts_known; ///< per load: how many cuts of its tetrahedron its region knew
    isxfem::CutReport m_frame_cut;         ///< the frame's cuts, all tools together
    // The run so far.
    std::size_t m_cut_tets = 0, m_recut = 0, m_crossed = 0, m_beside = 0, m_frames_left_whole = 0;
    std::size_t m_frame = 0;
    std::string m_fallback_reported; ///< the solver's preconditioner failure already reported (sim::newly_failed)
};

} // namespace vox::sim
