#pragma once
// A simulation method behind one interface: the mechanical model of a scene's object, what tools
// do to it, one solver step, and what the rest of the product reads of it (the surface for
// pictures and exports, the surface near a tool for the haptic loop, the frame's figures). The
// branched grid (sim/dbg_method.hpp) and Is-XFEM (sim/isxfem_method.hpp) are two classes behind
// it; the tool policy (sim/tool_policy.hpp) and the frame loop (sim/frame_loop.hpp) are written
// once against it, so a third method is one more class.
//
// Split of the work with the tool policy: the policy decides *when* a tool cuts (pressure at its
// edge, two-phase marking, strokes begun and ended); the method decides *where* (the stroke's
// swept geometry carried to its rest space) and *how* (voxels removed or faces opened,
// tetrahedra enriched).

#include "contact/obstacle.hpp"
#include "sim/piece_contact.hpp"
#include "contact/penalty_contact.hpp"
#include "contact/surface_points.hpp"
#include "contact/tool_shape.hpp"
#include "grid/label_grid.hpp"
#include "io/scene.hpp"
#include "io/tool_script.hpp"
#include "io/vtu_writer.hpp"
#include "surface/embedded_surface.hpp"

#include <nlohmann/json.hpp>

#include <array>
#include <cstdint>
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <vector>

namespace vox::sim {

/// One solver step, as every method reports it.
struct StepFigures {
    double step_ms = 0.0;
    double assembly_ms = 0.0; ///< rotations, forces and matrix
    double solve_ms = 0.0;    ///< preconditioner and CG
    int cg_iterations = 0;
    int newton_iterations = 0;
    double residual = 0.0;
    bool converged = true;
    int substeps = 0;
    double kinetic_energy_j = 0.0;
    std::optional<double> elastic_energy_j; ///< empty where the method does not measure it
    /// The largest displacement of the object's surface from rest (FrameLoop measures it the same
    /// way for every method): the material's, not that of an element corner lying outside it.
    double max_displacement_mm = 0.0;
    /// Elements inverted after the step (hexahedra: the deformation gradient at the material
    /// centroid; uncut tetrahedra: the signed volume of their nodes); 0 for a healthy run.
    std::size_t inverted_elements = 0;
    /// The largest stretch of any element (fem::ElementShapes::max_stretch: 1 at rest) and where
    /// that element is, mm: what tells a run that diverges (sim::k_runaway_stretch).
    double max_stretch = 1.0;
    std::array<double, 3> most_stretched_mm{};
    std::size_t asleep_pieces = 0;          ///< pieces at rest, not stepped (branched grid)
    bool energy_projected = false;          ///< the step created energy even split into 32 substeps, and lost it again
    /// The first solve created energy and was refused; the fuller one (Newton, substeps) converged.
    bool recovered = false;
    /// Why the preconditioner failed in this step and what took over ("" when it did not).
    std::string preconditioner_fallback;
};

/// What one tool's cut did in one frame (added over a frame's tools). Phases as the branched-grid
/// paper names them; a method leaves at zero what it has not.
struct CutFigures {
    double grid_update_ms = 0.0; ///< the object's discretisation changed (branched grid: BranchedGrid::update)
    double remesh_ms = 0.0;      ///< the surface remade along the cut (local remesh; Is-XFEM: the closure)
    double fem_update_ms = 0.0;  ///< the model and solver brought up to date, state carried over
    std::size_t removed_voxels = 0;
    std::size_t separated_faces = 0;
    std::size_t separated_voxels = 0; ///< voxels with a face opened
    std::size_t cut_elements = 0;     ///< elements the cut changed (either method)
    [[nodiscard]] bool changed() const { return removed_voxels + separated_faces + cut_elements > 0; }
    CutFigures& operator+=(const CutFigures& o);
};

/// What the tool policy has decided for one cutting tool in one frame.
struct CutOrder {
    bool touching = false; ///< the tool touches the object
    bool marking = false;  ///< two-phase: the tool is marking its cut (the object is held)
    bool cut = false;      ///< cut now: what the frame swept, or, marking, the whole marked path
};

/// How a vertex of Method::surface_mesh() is drawn.
enum class SurfaceMark : unsigned char {
    surface, ///< the object's own surface
    cut,     ///< made by a cut
    coupled  ///< in or beside an element whose pieces the cuts could not separate
};

/// A method's state at one moment, restorable (the viewer's undo).
class Checkpoint {
public:
    virtual ~Checkpoint() = default;
};

class Method {
public:
    virtual ~Method() = default;

    /// The scene's `solver.type`: "dbg", "isxfem" or "shape_matching".
    [[nodiscard]] virtual const char* name() const = 0;
    /// The simulated level of the scene's grid.
    [[nodiscard]] virtual int level() const = 0;
    /// Elements (hexahedra, tetrahedra) and degrees of freedom now.
    [[nodiscard]] virtual std::size_t element_count() const = 0;
    [[nodiscard]] virtual std::size_t dof_count() const = 0;
    /// Elements by grid level: one entry, unless the model holds two levels ("levels" as an object).
    [[nodiscard]] virtual std::map<int, std::size_t> elements_per_level() const { return {{level(), element_count()}}; }
    /// "CG, warped Cholesky preconditioner", ...; after a fallback, what took over and why.
    [[nodiscard]] virtual std::string linear_solver() const = 0;
    /// A line for the log: the model, its size and solver.
    [[nodiscard]] virtual std::string description() const = 0;

    // --- Tools, as sim::ToolPolicy drives them each frame: begin_tools, then for every placed
    // tool touch and (cutting tools) follow, and wet; then end_tools. ---

    virtual void begin_tools(std::size_t tool_count) = 0;
    /// Tool `tool` (shape `at`, moved since the last frame from `from`, or just arrived: null)
    /// pressed against the deformed surface: the contact, whose forces the method keeps as loads
    /// for the next step.
    virtual const contact::ContactResult& touch(std::size_t tool, const io::ToolSpec& spec, const contact::PlacedShape& at,
                                                const contact::PlacedShape* from) = 0;
    /// A cutting tool's frame: it moved from `from` (its pose at the frame's start) to `at`; the
    /// method carries its stroke on and cuts as `order` says.
    virtual CutFigures follow(std::size_t tool, const io::ToolSpec& spec, const io::ToolPose& from, const contact::PlacedShape& at,
                              const CutOrder& order) = 0;
    /// The tool is not placed this frame: its stroke ends.
    virtual void lift(std::size_t tool) = 0;
    /// A wetting tool adds `water` (0..1) to what it touched this frame.
    virtual void wet(std::size_t tool, double water) = 0;
    /// A drilling tool removes up to `volume_mm3` (with what earlier frames left over) of the
    /// material it touches at `at`, the voxels nearest its body first.
    virtual CutFigures drill(std::size_t tool, const io::ToolSpec& spec, const contact::PlacedShape& at, double volume_mm3) = 0;
    /// The frame's contact forces go to the solver for the next step, with those of the scene's
    /// obstacles (sim/obstacles.hpp) pressing on the surface as the frame's cuts left it.
    virtual void end_tools() = 0;

    /// One time step (or, static scenes, the equilibrium).
    virtual StepFigures step() = 0;

    // --- What others read. ---

    /// The deformed surface, world mm, closed along the cuts.
    [[nodiscard]] virtual surface::SurfaceMesh surface_mesh() const = 0;
    /// The object's voxels in rest space as sculpting left them (removed voxels gone), on the grid
    /// and with the metadata (source, scan size, segments) of the voxels it was built from: what
    /// is written back for the scan's own tools (io/label_map_writer.hpp).
    [[nodiscard]] virtual grid::LabelGrid rest_voxels() const = 0;
    /// The finite-element mesh for ParaView (io/vtu_writer.hpp), or nothing when the method cannot
    /// write it yet.
    [[nodiscard]] virtual std::optional<io::VtuMesh> fem_mesh() const { return std::nullopt; }
    /// Per vertex of surface_mesh(): what it is, and its water content (0..1).
    [[nodiscard]] virtual std::vector<SurfaceMark> surface_marks() const = 0;
    [[nodiscard]] virtual std::vector<float> surface_wetness() const = 0;
    /// Displacement (mm) and identity (surface::SurfaceVertex::key, the same in every method at
    /// one level) of each surface vertex that existed before any cut: comparisons between methods.
    [[nodiscard]] virtual std::vector<Eigen::Vector3d> surface_displacements_mm() const = 0;
    [[nodiscard]] virtual std::vector<std::uint64_t> surface_keys() const = 0;
    /// Fills `out` with the surface within `box` (world mm) as the haptic thread touches it with
    /// `tool` (at most out.capacity() points; out.truncated says when more were near).
    virtual void sample_surface(const Eigen::AlignedBox3d& box, const io::ToolSpec& tool, contact::SurfacePoints& out) const = 0;
    /// The same, as touch() presses it: the deformed surface itself, for the tool policy's proxy
    /// (sim/tool_policy.hpp). sample_surface's, but where a method hands the haptic loop another
    /// surface (shape matching: where its clusters' goals put it).
    virtual void sample_pressed_surface(const Eigen::AlignedBox3d& box, const io::ToolSpec& tool, contact::SurfacePoints& out) const
    {
        sample_surface(box, tool, out);
    }

    /// The object's condensed compliance where tool `tool` touched it last frame: under that
    /// contact's own load, spread as it is, the load-weighted displacement per newton one step
    /// gives (the tools' contact springs left out), mm/N. What the haptic patch at the contact is
    /// scaled to (contact/contact_patch.hpp). Nothing where the tool touched nothing or the method
    /// has no such measure (Is-XFEM, shape matching: docs/haptics.md).
    [[nodiscard]] virtual std::optional<double> contact_compliance_mm_per_n(std::size_t /*tool*/) { return std::nullopt; }

    /// Adds the frame's and the run's figures that only some methods have to stats.json: under
    /// the shared names where the branched grid's run named them first (scripts read those), the
    /// rest under the method's own key.
    virtual void add_frame_figures(nlohmann::json& /*frame*/) const {}
    virtual void add_summary_figures(nlohmann::json& /*summary*/) const {}
    /// Separate pieces of the object now.
    [[nodiscard]] virtual std::size_t piece_count() const = 0;
    /// The scene's obstacles (sim/obstacles.hpp), and the force they push the object with this
    /// frame, N, friction included.
    [[nodiscard]] virtual const std::vector<contact::Obstacle>& obstacles() const = 0;
    [[nodiscard]] virtual Eigen::Vector3d obstacle_force_n() const = 0;
    /// The object's contact with itself this frame (the scene's "piece_contact").
    [[nodiscard]] virtual PieceContactFigures piece_contact() const = 0;

    /// The same object at another level, from rest: the branched grid keeps its cuts (replayed on
    /// the new level's grid); Is-XFEM starts uncut (its cuts live in the tetrahedra of one level).
    [[nodiscard]] virtual std::unique_ptr<Method> at_level(int level) const = 0;
    /// Moves this simulation to `level` carrying its state on: positions, velocities, water,
    /// plastic strain, cuts and surface (a run whose frames miss their budget moves coarser:
    /// sim/level_governor.hpp). `preconditioner` as the scene's key says. False where the method
    /// cannot (Is-XFEM: its cracks live in one level's tetrahedra) or has no such level. Throws
    /// InputError when the object cannot be simulated there (a wet region holding no element's centre there),
    /// changing nothing.
    virtual bool move_to_level(int /*level*/, io::PreconditionerChoice /*preconditioner*/) { return false; }
    /// The coarsest level move_to_level() reaches.
    [[nodiscard]] virtual int coarsest_level() const { return level(); }

    // --- The cuts as a record (session journals: sim/journal.hpp). ---

    /// How many cuts were made so far (after an undo, fewer than before).
    [[nodiscard]] virtual std::size_t cut_count() const = 0;
    /// Cuts from the `from`-th on, in the order they were made, as JSON of the method's own form
    /// (the branched grid: the voxels each removed and faces each opened; Is-XFEM: each swept
    /// surface handed to the tetrahedra). Results, not the tool motions that made them: replaying
    /// them needs no solve and does not depend on the deformation.
    [[nodiscard]] virtual nlohmann::json cuts_since(std::size_t from) const = 0;
    /// Makes the cuts of `cuts` (as cuts_since gave them) on this object, in order: on the same
    /// object at the same level, uncut and at rest, the same voxels removed and faces opened, or
    /// the same cracks, as when they were made. Throws InputError for a record that does not fit
    /// the object (a voxel or tetrahedron it does not have).
    virtual void replay_cuts(const nlohmann::json& cuts) = 0;
    /// What the cuts do not fix, as numbers in the method's own order: positions and velocities
    /// (and the branched grid's water and plastic strain per element). After the same cuts are
    /// replayed, set_motion() puts the object back as it moved; it throws InputError when the
    /// count does not fit or a number is not finite, changing nothing.
    [[nodiscard]] virtual std::vector<double> motion() const = 0;
    virtual void set_motion(const std::vector<double>& numbers) = 0;

    /// The state now (model, cuts, solver), and back to it; null where the method cannot go back
    /// yet (Is-XFEM: docs/isxfem.md).
    [[nodiscard]] virtual std::unique_ptr<Checkpoint> checkpoint() const = 0;
    virtual void restore(const Checkpoint& checkpoint) = 0;
};

/// The volume enclosed by a closed surface (divergence theorem), mm^3: the same measure for every
/// method's surface_mesh().
[[nodiscard]] double enclosed_volume_mm3(const surface::SurfaceMesh& mesh);

/// Throws InputError unless `numbers` holds `expected` finite numbers (Method::set_motion).
void check_motion(const std::vector<double>& numbers, std::size_t expected);

/// A method's solver's fallback note (`note`, "" while its preconditioner works) when it is new
/// since the last call (`reported` keeps what was said): the step in which it failed says it once,
/// and the log warns. "" otherwise.
[[nodiscard]] std::string newly_failed(const std::string& note, std::string& reported);

} // namespace vox::sim
