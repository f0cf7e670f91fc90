#pragma once
// The branched grid (`"solver": {"type": "dbg"}`) behind the method interface: the scene's grid
// and its simulation at one level (sim/dbg_simulation.hpp), what the tools do to it (penalty
// contact on the embedded surface, voxels removed inside a cutting tool or faces opened where its
// section swept, water where a wetting tool touches), and every cut kept in order so that a
// checkpoint can rebuild the same grid node for node.

#include "cut/surface_contact.hpp"
#include "sim/dbg_simulation.hpp"
#include "sim/obstacles.hpp"
#include "sim/method.hpp"

#include <array>
#include <memory>
#include <unordered_set>
#include <set>
#include <vector>

namespace vox::sim {

/// The voxels one cut removed and the faces it opened, in the order the cuts were made: replaying
/// them on the same object rebuilds the same grid.
struct CutRecord {
    std::vector<grid::Coord> removed;
    std::vector<std::pair<grid::Coord, int>> faces;
};

class DbgMethod final : public Method {
public:
    /// Builds the grid of `labels` with levels up to `grid_levels` (at least `level`; coarser ones
    /// serve the multigrid preconditioner) and the simulation at `level`. Throws the scene's
    /// InputError when a constraint or load box holds no voxel centre.
    DbgMethod(const io::Scene& scene, std::shared_ptr<const grid::LabelGrid> labels, int level, int grid_levels);
    /// The same, on a grid already built (levels chosen by "levels": "auto" were measured on it).
    DbgMethod(const io::Scene& scene, std::shared_ptr<const grid::LabelGrid> labels, std::unique_ptr<grid::BranchedGrid> grid, int level);
    ~DbgMethod() override;

    /// "dbg", or "shape_matching" when shape matching steps the grid's nodes (sim/dbg_simulation.hpp).
    [[nodiscard]] const char* name() const override { return io::solver_type_name(m_scene.solver.type).data(); }
    [[nodiscard]] int level() const override { return m_level; }
    [[nodiscard]] std::size_t element_count() const override { return m_sim->model().elements().size(); }
    [[nodiscard]] std::map<int, std::size_t> elements_per_level() const override;
    [[nodiscard]] std::size_t dof_count() const override { return m_sim->solver().dof_count(); }
    [[nodiscard]] std::string linear_solver() const override;
    [[nodiscard]] std::string description() const override;

    void begin_tools(std::size_t tool_count) override;
    const contact::ContactResult& touch(std::size_t tool, const io::ToolSpec& spec, const contact::PlacedShape& at,
                                        const contact::PlacedShape* from) override;
    CutFigures follow(std::size_t tool, const io::ToolSpec& spec, const io::ToolPose& from, const contact::PlacedShape& at,
                      const CutOrder& order) override;
    void lift(std::size_t tool) override
    {
        if (tool < m_stroke.size()) m_stroke[tool].going = false;
    }
    void wet(std::size_t tool, double water) override;
    CutFigures drill(std::size_t tool, const io::ToolSpec& spec, const contact::PlacedShape& at, double volume_mm3) override;
    void end_tools() override;
    StepFigures step() override;

    [[nodiscard]] surface::SurfaceMesh surface_mesh() const override;
    [[nodiscard]] grid::LabelGrid rest_voxels() const override;
    [[nodiscard]] std::optional<io::VtuMesh> fem_mesh() const override;
    [[nodiscard]] std::vector<SurfaceMark> surface_marks() const override;
    [[nodiscard]] std::vector<float> surface_wetness() const override;
    [[nodiscard]] std::vector<Eigen::Vector3d> surface_displacements_mm() const override;
    [[nodiscard]] std::vector<std::uint64_t> surface_keys() const override;
    void sample_pressed_surface(const Eigen::AlignedBox3d& box, const io::ToolSpec& tool, contact::SurfacePoints& out) const override;
    void sample_surface(const Eigen::AlignedBox3d& box, const io::ToolSpec& tool, contact::SurfacePoints& out) const override;
    std::optional<double> contact_compliance_mm_per_n(std::size_t tool) override;
    [[nodiscard]] std::size_t piece_count() const override;
    [[nodiscard]] const std::vector<contact::Obstacle>& obstacles() const override { return m_obstacles; }
    [[nodiscard]] Eigen::Vector3d obstacle_force_n() const override { return m_obstacle_force; }
    [[nodiscard]] PieceContactFigures piece_contact() const override { return m_piece_contact; }
    void add_frame_figures(nlohmann::json& frame) const override;
    void add_summary_figures(nlohmann::json& summary) const override;

    [[nodiscard]] std::unique_ptr<Method> at_level(int level) const override;
    bool move_to_level(int level, io::PreconditionerChoice preconditioner) override;
    [[nodiscard]] int coarsest_level() const override { return m_grid->max_level(); }
    [[nodiscard]] std::size_t cut_count() const override;
    [[nodiscard]] nlohmann::json cuts_since(std::size_t from) const override;
    void replay_cuts(const nlohmann::json& cuts) override;
    [[nodiscard]] std::vector<double> motion() const override;
    void set_motion(const std::vector<double>& numbers) override;
    [[nodiscard]] std::unique_ptr<Checkpoint> checkpoint() const override;
    void restore(const Checkpoint& checkpoint) override;

    /// What only the branched grid has: its grid, simulation (pictures of voxels and elements,
    /// level choice, benchmarks) and the cuts so far.
    [[nodiscard]] const grid::BranchedGrid& grid() const { return *m_grid; }
    [[nodiscard]] DbgSimulation& simulation() { return *m_sim; }
    [[nodiscard]] const DbgSimulation& simulation() const { return *m_sim; }
    [[nodiscard]] const std::vector<CutRecord>& cuts() const { return m_cuts; }
    /// Voxels that have had a face opened since the start.
    [[nodiscard]] std::size_t separated_voxels() const { return m_separated.size(); }

private:
    /// Carries a separating tool's section (world mm) back to rest space for this frame of its
    /// stroke: by the material's mean displacement around it, held across the blade's plane for
    /// the stroke, and laid into the plane its edge sweeps.
    void carry_to_rest(std::size_t tool, const io::ToolSpec& spec, const io::ToolPose& from, const contact::PlacedShape& at,
                       const CutOrder& order, std::vector<Eigen::Vector3d>& rest_section);
    /// An edge cutting as it presses: the section reaches past the rest position of the surface
    /// points the edge presses on.
    void reach_past_edge(std::size_t tool, const contact::PlacedShape& at, double margin_mm, std::vector<Eigen::Vector3d>& rest_section) const;
    /// Applies one cut, logging it; the tools' contacts are carried over to the rebuilt model.
    CutFigures apply(std::vector<grid::Coord> removed, std::vector<std::pair<grid::Coord, int>> faces);

    io::Scene m_scene;
    std::shared_ptr<const grid::LabelGrid> m_labels;
    int m_level = 1;
    int m_grid_levels = 1;
    std::unique_ptr<grid::BranchedGrid> m_grid;
    std::unique_ptr<DbgSimulation> m_sim;
    std::vector<CutRecord> m_cuts;
    std::unordered_set<std::uint32_t> m_separated; ///< voxel slots with an opened face
    std::unordered_set<std::uint64_t> m_uncut;     ///< surface vertex keys before any cut
    std::vector<contact::Obstacle> m_obstacles;
    std::vector<contact::FrictionAnchors> m_anchors; ///< per obstacle
    std::size_t m_obstacle_pairs = 0;                ///< the solver's first pair contacts are the obstacles' pushes
    Eigen::Vector3d m_obstacle_force = Eigen::Vector3d::Zero(); ///< on the object, this frame
    PieceContactFigures m_piece_contact;                        ///< this frame
    // Per tool, this frame and across frames.
    std::vector<cut::SurfaceContact> m_touch;
    std::vector<Eigen::AlignedBox3d> m_tool_reach; ///< this frame's tools, grown by k_sleep_tool_mm (DbgSimulation::set_tool_reach)
    std::vector<Eigen::AlignedBox3d> m_region_reach; ///< two levels: this frame's tools, grown by fine_radius_mm (DbgSimulation::follow_tools)
    double m_region_move_ms = 0.0; ///< two levels: this frame's move of the fine region (0: it stayed)
    std::size_t m_region_moves = 0;
    std::vector<bool> m_touched;  ///< placed (and touched) this frame
    std::vector<bool> m_fresh;    ///< m_touch[k] is up to date with the model (no cut since)
    /// Per tool: its contact's compliance as last measured (a solve of the step's system), and
    /// the frames since; measured again every k_compliance_frames (it changes slowly with the
    /// deformation) or when the tool comes into contact.
    struct Compliance {
        std::optional<double> mm_per_n;
        int age = 0;
    };
    std::vector<Compliance> m_compliance;
    std::vector<double> m_drill_budget; ///< per tool: volume a drill may still remove, below one voxel's, mm^3
    /// A separating tool's cutting section at the previous frame (within a stroke that has cut,
    /// at its last cut), in rest space: a frame's cut opens what the section swept since.
    std::vector<std::vector<Eigen::Vector3d>> m_previous_section;
    /// Two-phase tools: the section where the marking began (rest space).
    std::vector<std::vector<Eigen::Vector3d>> m_marked_from;
    /// A separating tool's stroke: the blade's plane normal, the material's displacement across it
    /// (mm) where the stroke began, and the plane its edge sweeps. A stroke goes on while the
    /// blade turns by less than k_stroke_turn_cos a frame (as Is-XFEM's blade strokes:
    /// sim/blade_stroke.hpp) and touches the object at least every k_stroke_gap_s.
    struct StrokeCarry {
        bool going = false;
        Eigen::Vector3d normal = Eigen::Vector3d::Zero();
        double across_mm = 0.0;
        Eigen::Vector3d cut_normal = Eigen::Vector3d::Zero(); ///< of the plane the edge sweeps
        double untouched_s = 0.0;                              ///< since the blade last touched
        bool has_cut = false;                                  ///< some frame of it opened faces
        std::set<std::array<int, 4>> opened;                   ///< the faces it opened: voxel x, y, z, axis
    };
    /// Leaves out of a stroke's new faces those parallel to a face it opened already and one voxel
    /// beside it, and adds the rest to its faces.
    static void keep_one_sheet(StrokeCarry& stroke, std::vector<std::pair<grid::Coord, int>>& faces);
    std::vector<StrokeCarry> m_stroke;
    static constexpr double k_stroke_turn_cos = 0.98480775301220802; // cos 10 degrees
    static constexpr double k_stroke_gap_s = 0.2;
    std::string m_fallback_reported; ///< the solver's preconditioner failure already reported (sim::newly_failed)
};

} // namespace vox::sim
