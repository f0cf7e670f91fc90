#pragma once
// A scene made ready to simulate at one level: the mechanical model, the solver with the scene's
// constraints, loads, gravity, materials (plasticity, wetting) and wet regions, its
// preconditioner, and the surface it moves. The branched-grid method (sim/dbg_method.hpp), the level choice and the
// benchmarks all build their simulations here, so they simulate the same thing. A cut changes the grid and
// the surface locally, then rebuilds the model at the same level carrying the state over.

#include "cut/model_surface.hpp"
#include "fem/implicit_solver.hpp"
#include "fem/rigid_body.hpp"
#include "io/scene.hpp"
#include "io/scene_object.hpp"
#include "sim/mixed_region.hpp"
#include "sim/supports.hpp"

#include <memory>
#include <span>
#include <string>
#include <utility>

namespace vox::sim {

/// The grid of a scene's object, with levels up to `max_level` (coarser levels than the simulated
/// one serve the multigrid preconditioner).
[[nodiscard]] grid::BranchedGrid build_scene_grid(const io::Scene& scene, const grid::LabelGrid& labels, int max_level);

/// Whether simulating `scene` at `level` of `grid` would pick the multigrid preconditioner, which
/// needs the grid's coarser levels; without it a grid up to `level` is enough (and cuts update
/// fewer levels).
[[nodiscard]] bool wants_multigrid(const io::Scene& scene, const grid::BranchedGrid& grid, int level);

/// The smoothing of "smooth_surface" (on by default): a windowed-sinc filter of this degree and
/// pass band (surface/embedded_surface.hpp), strong enough to take out the terraces of 1.5 mm
/// CT slices while keeping the shape and, exactly, the enclosed volume.
inline constexpr int k_smoothing_iterations = 20;

/// A piece sleeps (is not stepped) once every node of it has been slower than this for
/// k_sleep_after_s, with no tool within k_sleep_tool_mm and no scene load on it; a tool coming
/// that near, or a cut, wakes it.
inline constexpr double k_sleep_speed_m_s = 1e-3;
inline constexpr double k_sleep_after_s = 0.5;
inline constexpr double k_sleep_tool_mm = 10.0;
inline constexpr double k_smoothing_passband = 0.05;

/// Smooths a scene's surface at rest, once, as it is extracted (both methods), unless the
/// scene's object says "smooth_surface": false.
void smooth_scene_surface(const io::Scene& scene, const grid::BranchedGrid& grid, surface::EmbeddedSurface& surface);

/// Milliseconds spent applying one cut.
struct CutTimings {
    double grid_update_ms = 0.0; ///< BranchedGrid::update
    double remesh_ms = 0.0;      ///< EmbeddedSurface::update
    double fem_update_ms = 0.0;  ///< the model, solver and surface embedding rebuilt, state carried over
};

class DbgSimulation {
public:
    /// Throws the scene's InputError when a constraint or load box holds no voxel centre.
    /// Keeps a reference to `grid`.
    DbgSimulation(const io::Scene& scene, const grid::BranchedGrid& grid, int level);
    /// The simulation `from` at another level of the same grid, with `preconditioner` (the scene's
    /// choice, "auto" resolved there), carrying everything over: positions, velocities, water and
    /// plastic strain (cut/state_transfer.hpp), the surface with its cuts and smoothing
    /// (re-embedded), and the pieces "unheld_pieces": "hold" holds. `from` gives its surface up and
    /// is left only to be destroyed. Throws the scene's InputError when a constraint or load box
    /// holds no voxel centre, or the multigrid has no coarser level there; `from` is then
    /// unchanged.
    DbgSimulation(DbgSimulation& from, int level, io::PreconditionerChoice preconditioner);

    [[nodiscard]] const fem::HexModel& model() const { return *m_model; }
    [[nodiscard]] fem::ImplicitSolver& solver() { return *m_solver; }
    [[nodiscard]] const fem::ImplicitSolver& solver() const { return *m_solver; }
    [[nodiscard]] const cut::ModelSurface& surface() const { return *m_model_surface; }
    /// The pieces no constraint reached as the run started, held in place ("unheld_pieces": "hold").
    [[nodiscard]] std::size_t held_piece_count() const { return m_held_pieces; }
    /// Elements holding rigid material, and the pieces moving as rigid bodies (fem/rigid_body.hpp).
    [[nodiscard]] std::size_t rigid_element_count() const { return m_rigid_elements; }
    [[nodiscard]] std::size_t rigid_body_count() const { return m_bodies.size(); }
    /// "Jacobi (matrix-free)", "warped Cholesky", "multigrid (3 levels)".
    [[nodiscard]] const std::string& linear_solver() const { return m_linear_solver; }

    /// One frame's step: the finite elements, then the rigid bodies under the same contact; pieces
    /// at rest sleep (see k_sleep_speed_m_s) until a tool comes near or a cut rebuilds the model.
    fem::StepStats step();
    /// Where the tools are this frame: world boxes (mm) around each placed tool. A sleeping piece
    /// whose box meets one wakes; an awake piece within one does not fall asleep.
    void set_tool_reach(std::vector<Eigen::AlignedBox3d> boxes_mm) { m_tool_reach = std::move(boxes_mm); }
    /// Pieces asleep now.
    [[nodiscard]] std::size_t asleep_piece_count() const;

    /// Removes fine voxels and disconnects faces of `grid` (the grid this simulation was built
    /// on), updates the surface locally and rebuilds the model, carrying positions, velocities,
    /// water and plastic strain over (cut/state_transfer.hpp).
    CutTimings apply_cut(grid::BranchedGrid& grid, std::span<const grid::Coord> removed,
                         std::span<const std::pair<grid::Coord, int>> faces);

    /// Two levels: the fine region (sim/mixed_region.hpp), and moving it after the tools, whose
    /// reach this frame is `reach_mm` (world boxes of their outer shapes grown by fine_radius_mm;
    /// none placed: the region stays). Returns whether the region moved: the model was rebuilt
    /// on the new region, carrying positions, velocities, water and plastic strain
    /// (cut/state_transfer.hpp), and node numbers changed. One level: false, always.
    [[nodiscard]] const RegionCells& region() const { return m_region; }
    bool follow_tools(std::span<const Eigen::AlignedBox3d> reach_mm);
    /// Two levels: the model rebuilt on the fine region `cells`, carrying the state over (a restored
    /// checkpoint's region). Does nothing when the region is already that.
    void set_region(RegionCells cells);

private:
    /// What a build starts from: the scene (the wet regions are applied and the pieces to hold
    /// found), another level's simulation, or the same level before a cut. Boxes that hold no material
    /// are errors except after a cut (it may have taken their material).
    /// A move of the fine region keeps the grid: what the boxes hold stays measured.
    enum class Build { first, level_change, cut, region };
    /// Model, solver, preconditioner, materials, constraints and loads at m_level. After a cut,
    /// `previous` and `report` let unchanged elements keep their matrices (after a move of the fine
    /// region, `previous` alone: the grid is the same), and `previous_solver`
    /// lends its matrix pattern when the elements sit on the same nodes.
    void build(Build kind, const fem::HexModel* previous = nullptr, const grid::UpdateReport* report = nullptr,
               const fem::ImplicitSolver* previous_solver = nullptr);

    /// "unheld_pieces": "hold": fixes every node of the pieces no constraint reaches (found when
    /// `first`; after cuts, the elements holding their voxels). `constrained` flags the nodes the
    /// scene's constraint boxes hold; the held nodes get all three axes in `held_axes`.
    void hold_unheld_pieces(bool first, const std::vector<unsigned char>& constrained, std::vector<unsigned>& held_axes);
    /// After a state carried from another model: what is held back at rest (constraints, rigid
    /// anchoring, held pieces: the interpolation would move a held node by the field beside it); a
    /// rigid body's nodes are where its body put them.
    void rest_held_nodes();

    io::Scene m_scene;
    const grid::BranchedGrid* m_grid;
    std::vector<unsigned char> m_rigid_material; ///< per grid material (sim/rigid_parts.hpp)
    std::vector<unsigned char> m_held_voxels; ///< per fine voxel slot: held by "unheld_pieces": "hold"
    std::size_t m_held_pieces = 0;
    std::vector<BoxMaterial> m_boxes; ///< what each constraint box, then each load box, holds at m_level
    /// "levels" as an object: the two-level selection (m_level is its fine level) refining
    /// m_region; null for one level.
    std::unique_ptr<grid::MixedLevels> m_mixed;
    RegionCells m_region;
    int m_level;
    std::unique_ptr<fem::HexModel> m_model;
    std::unique_ptr<fem::ImplicitSolver> m_solver;
    std::unique_ptr<surface::EmbeddedSurface> m_surface;
    std::unique_ptr<cut::ModelSurface> m_model_surface;
    std::string m_linear_solver;
    io::PreconditionerChoice m_choice = io::PreconditionerChoice::automatic; ///< resolved, at the last build
    std::size_t m_rigid_elements = 0;
    /// A piece of the model (elements joined through nodes) that may sleep.
    struct Piece {
        std::vector<std::uint32_t> nodes;
        bool free = false;      ///< some node of it is not held
        bool can_sleep = false; ///< dynamic, some node free, no scene load, nothing plastic, not a rigid body
        double rest_s = 0.0;    ///< how long every node has been slower than k_sleep_speed_m_s
        bool asleep = false;
        Eigen::AlignedBox3d box_mm; ///< where it sleeps, world mm
    };
    /// The pieces of the model as built (all awake); `piece` per element (cut::element_pieces).
    void find_pieces(const std::vector<std::uint32_t>& piece);
    /// Every piece that could move sleeps (and no rigid body moves): the step is skipped whole.
    [[nodiscard]] bool all_asleep() const;
    /// Hands the asleep nodes to the solver, unless all_asleep().
    void apply_sleep();
    /// The step of the awake pieces and the rigid bodies.
    fem::StepStats step_awake();
    std::vector<Piece> m_pieces;
    std::vector<unsigned char> m_solver_asleep; ///< per node: what the solver was last told (set_asleep)
    fem::StepStats m_resting;                   ///< the last step taken, whose energy a skipped step reports
    std::vector<Eigen::AlignedBox3d> m_tool_reach;
    std::vector<fem::RigidBody> m_bodies;
    std::vector<std::int32_t> m_body_of_node; ///< per node: its body, or -1
};

} // namespace vox::sim
