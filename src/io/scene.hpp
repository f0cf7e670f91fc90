#pragma once
// Scene files: one JSON document saying what to simulate (the object, its materials, the solver,
// gravity, constraints, loads, tools, a tool script and the output). Users' reference:
// docs/scene-format.md. Every key carries its unit in its name; the reader is strict
// (io/json_reader.hpp): an unknown key, a wrong type, a value out of range or a missing file is an
// InputError naming the key path.

#include "core/error.hpp"
#include "grid/phantom.hpp"
#include "io/selection.hpp"

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <nlohmann/json_fwd.hpp>

#include <array>
#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <map>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

namespace vox::io {

/// Where the object's voxels come from.
enum class ObjectKind {
    volume,  ///< a scan volume (CT, MRI segmentation) and a selection of its voxels
    phantom, ///< a generated shape
    mesh,    ///< a closed triangle mesh, voxelised
};

/// What becomes of the object's pieces that no constraint box reaches (a CT's loose fragments, a
/// scanner's head holder), from the start of a run. Pieces a cut frees later fall.
enum class UnheldPieces {
    hold,      ///< "hold" (default): they stay where the scan has them (every node fixed)
    fall,      ///< "fall": they move freely, under gravity and tools
    leave_out, ///< "leave_out": they are not simulated at all
    rigid,     ///< "rigid": each moves as one rigid body, under gravity and tools (branched grid)
};

/// The object to simulate: its source, and the coarsening level it is simulated at.
/// Two levels in one model (key "levels" as an object).
struct MixedLevelsSpec {
    int fine = 1;                ///< 1 .. 5
    int coarse = 3;              ///< fine + 1 .. 6
    double fine_radius_mm = 20.0; ///< > 0
};

struct SceneObject {
    ObjectKind kind = ObjectKind::phantom;
    /// volume, mesh: the file, absolute (resolved against the scene's folder); it existed when
    /// the scene was read. A volume may be a DICOM folder.
    std::filesystem::path file;
    /// volume, a 3D Slicer segmentation: the picked segments' colours by label (their colours in
    /// pictures); empty otherwise.
    std::map<std::int32_t, Eigen::Vector3d> label_colors;
    std::map<std::int32_t, std::string> label_names; ///< the picked segments' names, by label
    /// volume: key "series", the DICOM series read (its number in `info`, or its UID); "": the only one.
    std::string series;
    /// volume: the voxels kept (labels keep their value, a threshold window gives label 1); empty
    /// when the scene has no "select": every non-zero voxel, keeping its value as label.
    Selection select;
    /// phantom: shape, sizes (mm) and voxel size (mm); every size a whole number of voxels.
    grid::PhantomSpec phantom;
    /// mesh: voxel edge length, mm (after scaling); unset: the longest side / 128.
    std::optional<double> voxel_mm;
    /// mesh: millimetres per mesh unit (the mesh's vertices are multiplied by it).
    double scale_mm_per_unit = 1.0;
    /// The coarsening level simulated, 0..6: an element spans 2^levels voxels per axis. Default 3,
    /// the level of the branched-grid paper's liver (Jerabkova et al. 2010, section 4: about 13,000
    /// voxels, three coarsening levels, 104 elements).
    int levels = 3;
    /// "levels": "auto": the run picks the level itself, by step_budget_ms (the finest level
    /// whose measured step fits) or max_error (the coarsest level whose deflection differs from
    /// the next finer level's by at most this fraction); exactly one of the two is given.
    bool auto_levels = false;
    /// "levels": {"fine": F, "coarse": C, "fine_radius_mm": R}: the branched grid simulates level F
    /// within R mm of each tool's outer shape where the run starts and level C elsewhere
    /// (grid/mixed_levels.hpp); `levels` is then C. Unset: one level.
    std::optional<MixedLevelsSpec> mixed_levels;
    /// Key "unheld_pieces"; unset: hold, or fall when the scene has obstacles (they catch it).
    UnheldPieces unheld = UnheldPieces::hold;
    bool unheld_given = false; ///< the file set "unheld_pieces"
    /// Key "smooth_surface": the surface is smoothed at rest (windowed sinc, volume kept) so that
    /// slice terraces and voxel steps do not show; false keeps the voxel steps. Unset: see
    /// smooths_surface().
    std::optional<bool> smooth_surface;
    std::optional<double> step_budget_ms;
    std::optional<double> max_error;
};

/// Müller & Gross (2004) plasticity: when the elastic strain's norm exceeds yield_strain, a part
/// creep_per_s * dt of it becomes plastic each step; the plastic strain's norm stays at most
/// max_strain. Absent: the material is elastic.
struct Plasticity {
    double yield_strain = 0.01;  ///< > 0
    double creep_per_s = 20.0;   ///< >= 0; creep_per_s * dt_s above 1 acts as 1
    double max_strain = 0.5;     ///< > 0
};

/// How water softens a material: at water content w in [0, 1], stiffness and plastic yield are
/// scaled by 1 - (1 - ratio) w (linear between dry, w = 0, and soaked, w = 1).
struct Wetting {
    double stiffness_ratio = 0.2; ///< in (0, 1]
    double yield_ratio = 0.5;     ///< in (0, 1]
};

/// Linear elastic material, SI units.
struct Material {
    /// Young's modulus E, Pa (> 0).
    double youngs_modulus_pa = 3e4;
    /// Poisson's ratio nu, dimensionless, in (-1, 0.5).
    double poisson_ratio = 0.45;
    /// Mass density, kg/m^3 (> 0).
    double density_kg_m3 = 1000.0;
    std::optional<Plasticity> plasticity;
    Wetting wetting;
    /// Key "rigid": the material does not deform (bone, a table, a holder). It has no finite
    /// elements of its own: the elements holding any of it are held in place, and the soft
    /// material attached to them with them; a piece made of rigid material alone that no
    /// constraint holds moves as one rigid body (branched grid). Still cut, drilled and touched.
    bool rigid = false;
};

/// Water content given to the elements whose material centroid lies in a box.
struct WetRegion {
    Eigen::Vector3d box_min_mm, box_max_mm;
    double water = 1.0; ///< in [0, 1]
};

/// The preconditioner of the conjugate-gradient solves.
enum class PreconditionerChoice { automatic, jacobi, cholesky, multigrid };

/// "auto", "jacobi", "cholesky" or "multigrid", as scene files write it.
[[nodiscard]] std::string_view preconditioner_name(PreconditionerChoice p);

/// The method (see DESIGN.md): dynamic branched grid, tetrahedra with Is-XFEM, or adaptive
/// hierarchical shape matching on the branched grid's levels.
enum class SolverType { dbg, isxfem, shape_matching };

/// "dbg", "isxfem" or "shape_matching", as scene files write it.
[[nodiscard]] std::string_view solver_type_name(SolverType type);
/// The method a name from that list means (a command line's --solver); throws InputError otherwise.
[[nodiscard]] SolverType solver_type_named(std::string_view name);

/// What a frame computes.
enum class SolverMode {
    dynamic,            ///< "dynamic": one implicit time step of dt_s per frame (inertia and damping)
    static_equilibrium, ///< "static": every frame solves to equilibrium under the frame's loads
};

/// Time stepping and linear solve.
struct SolverSettings {
    SolverType type = SolverType::dbg;
    /// Key "mode": "dynamic" (default) or "static" (quasi-static: every frame is solved to
    /// equilibrium by Newton iterations on the corotational system, until the force residual
    /// relative to the load meets cg_tolerance; extra frames then change nothing).
    SolverMode mode = SolverMode::dynamic;
    /// Time step, s (> 0).
    double dt_s = 0.01;
    /// Relative residual at which the conjugate-gradient solve stops, in (0, 1); in static mode
    /// also the relative force residual at which the Newton iterations stop.
    double cg_tolerance = 1e-6;
    /// Conjugate-gradient iteration cap per solve (>= 1).
    int cg_max_iterations = 200;
    /// Rayleigh damping, mass part: alpha in C = alpha M + beta K, 1/s (>= 0).
    double rayleigh_mass_per_s = 0.5;
    /// Rayleigh damping, stiffness part: beta in C = alpha M + beta K, s (>= 0).
    double rayleigh_stiffness_s = 0.002;
    /// Static mode: Newton iteration cap per frame (>= 1).
    int newton_max_iterations = 30;
    /// Key "preconditioner": "auto" (default), "jacobi", "cholesky", "multigrid".
    PreconditionerChoice preconditioner = PreconditionerChoice::automatic;
    /// Key "mass": "lumped" (default: row sums, diagonal) or "consistent".
    bool lumped_mass = true;
    /// isxfem: the enrichment parameter k in [0, 1] of Is-XFEM (0: standard XFEM); default 0.1,
    /// the sculpting paper's.
    double isxfem_k = 0.1;
    double isxfem_regularisation_lambda = 0.0;     ///< isxfem: A + lambda I on enriched dofs below the threshold (relative to the mean diagonal)
    double isxfem_regularisation_threshold = 1e-4; ///< isxfem: the volume ratio below which an enriched dof is regularised
    /// shape_matching (shape/shape_matching.hpp): key "cluster_levels", levels of clusters above
    /// the simulated one (0 .. 5, default 2); "adaptive" (default true: the paper's termination,
    /// subdivision and origination conditions; false: every level and cluster, classic
    /// hierarchical shape matching); "max_iterations", shape-matching iterations a step (default
    /// 60); "termination_rate" in (0, 1) (default 0.01); "subdivision_strain" (default 1e-4);
    /// "global_step" (default true: the simulated level's iterations solve the global step;
    /// false: the paper's averaging, particle by particle).
    int sm_cluster_levels = 2;
    bool sm_adaptive = true;
    bool sm_global_step = true;
    int sm_max_iterations = 60;
    double sm_termination_rate = 0.01;
    double sm_subdivision_strain = 1e-4;
};

enum class ConstraintType {
    fixed, ///< the nodes do not move
    slide, ///< the nodes are held along the listed world axes and move freely along the others
};

/// Boundary condition on the material whose voxel centres lie in an axis-aligned box, boundary
/// included, the same at every level (sim/supports.hpp: each such voxel holds the corner of its
/// element nearest to it). A box that holds no voxel centre is an error.
struct Constraint {
    ConstraintType type = ConstraintType::fixed;
    /// Box corner with the smallest coordinates, world mm.
    Eigen::Vector3d box_min_mm = Eigen::Vector3d::Zero();
    /// Box corner with the largest coordinates, world mm (>= box_min_mm on every axis).
    Eigen::Vector3d box_max_mm = Eigen::Vector3d::Zero();
    /// World axes (x, y, z) along which the nodes are held: all three for fixed, the listed one or
    /// two for slide (a roller holds the two axes across its rolling direction; a symmetry plane
    /// x = 0 holds x).
    std::array<bool, 3> held_axes{true, true, true};
};

enum class ObstacleShape { plane, box, mesh };

/// A static, solid obstacle the object rests on or is pushed against (a table, a support, a
/// tray); tools pass through it. Contact is the tools' penalty model with Coulomb friction
/// (contact/obstacle.hpp): a flat face pressed 1 mm into it over 1 cm^2 is pushed back with
/// stiffness_n_per_mm newtons.
struct Obstacle {
    ObstacleShape shape = ObstacleShape::plane;
    /// plane: a point on it, world mm, and its unit normal (normalised when read); solid on the
    /// side opposite the normal.
    Eigen::Vector3d point_mm = Eigen::Vector3d::Zero();
    Eigen::Vector3d normal = Eigen::Vector3d::UnitZ();
    /// box: its min and max corners, world mm; solid.
    Eigen::Vector3d box_min_mm = Eigen::Vector3d::Zero();
    Eigen::Vector3d box_max_mm = Eigen::Vector3d::Zero();
    /// mesh: a closed surface mesh, absolute path (it existed when read), solid inside; placed by
    /// scaling its vertices by `scale`, turning by `orientation` and moving by `position_mm`.
    std::filesystem::path mesh;
    Eigen::Vector3d position_mm = Eigen::Vector3d::Zero();
    Eigen::Quaterniond orientation = Eigen::Quaterniond::Identity();
    double scale = 1.0;
    /// Coulomb friction coefficient, [0, 10]: sliding along the obstacle is resisted by up to
    /// friction x the normal force.
    double friction = 0.3;
    /// Penalty stiffness per cm^2 of contact, N/mm, in (0, 1e4].
    double stiffness_n_per_mm = 10.0;
};

/// Key "piece_contact": contact of the object with itself (pieces cut free on the rest, the walls
/// of a cut pressed together, folds): the tools' penalty model, vertex against face
/// (contact/piece_contact.hpp), frictionless. Off unless the scene turns it on (`true`, or an
/// object setting its stiffness): with a blade in a slit it is not yet stable (docs/fem.md).
struct PieceContactSettings {
    bool enabled = false;
    /// Penalty stiffness per cm^2 of contact, N/mm, in (0, 1e4].
    double stiffness_n_per_mm = 10.0;
};

/// An external force on the material whose voxel centres lie in an axis-aligned box, boundary
/// included: a total force, world frame, shared equally by those voxels, each share going to its
/// element's corners by the trilinear weights at its centre (the same force and moment at every
/// level). A box that holds no voxel centre is an error found when the grid exists.
struct Load {
    /// Box corner with the smallest coordinates, world mm.
    Eigen::Vector3d box_min_mm = Eigen::Vector3d::Zero();
    /// Box corner with the largest coordinates, world mm (>= box_min_mm on every axis).
    Eigen::Vector3d box_max_mm = Eigen::Vector3d::Zero();
    /// Total force on the box's material, N, world frame.
    Eigen::Vector3d force_n = Eigen::Vector3d::Zero();
};

enum class ToolShape {
    blade,   ///< a thin box
    scalpel, ///< a pointed surgical blade
    sphere,   ///< a ball
    cylinder, ///< a solid cylinder along the tool's z, flat ends (a drill's shaft, a flat burr)
    mesh,     ///< any closed triangle mesh
};

/// What a tool does where it meets the object. Every tool pushes with its outer shape (the inner
/// shape grown by ToolSpec::push_margin_mm); the action says what the inner shape does besides.
enum class ToolAction {
    push, ///< deforms the object and never cuts ("push")
    cut,  ///< the inner shape cuts where it reaches material and the mean contact pressure on the
          ///< outer shape is at or above ToolSpec::cut_pressure_pa ("cut")
    wet,  ///< raises the water content of the elements it touches at ToolSpec::wet_rate_per_s ("wet")
    drill, ///< a spinning burr: removes the material it touches at a rate that grows with the
           ///< pressing force and the burr's speed (ToolSpec::burr_speed_rpm, drill_rate_mm3_per_n_rev) ("drill")
};

/// What a cut does to the fine voxels the inner shape reaches.
enum class CutMode {
    remove,   ///< the voxels are taken away: the tool carves ("remove")
    separate, ///< the voxel faces the inner shape crosses are disconnected: the material parts along
              ///< the cut and keeps its volume ("separate")
};

/// The action a tool has when the scene gives none: cut for blades and scalpels, push for spheres
/// and meshes.
[[nodiscard]] constexpr ToolAction default_tool_action(ToolShape shape)
{
    return shape == ToolShape::blade || shape == ToolShape::scalpel ? ToolAction::cut : ToolAction::push;
}

/// A script-driven tool's coupling spring, N/mm, where the scene gives none: stiff beside the
/// contact (5 N/mm per cm^2), so the proxy is where the script puts it until the material holds it.
constexpr double k_script_coupling_n_per_mm = 100.0;

/// A tool's `"device_frame"` (ToolSpec::device_frame).
struct DeviceFrameSpec {
    Eigen::Vector3d origin_mm = Eigen::Vector3d::Zero();
    Eigen::Quaterniond rotation = Eigen::Quaterniond::Identity();
    double scale = 1.0; ///< scene mm per device mm, in (0, 100]
};

/// A tool the script (or a haptic device) moves. Lengths in the tool's own frame, mm.
///
/// Contact model (docs/scene-format.md, "tools"): the shape below is the inner (cutting) shape;
/// the outer (pushing) shape is the inner one grown by push_margin_mm. Where the outer shape
/// overlaps the object by a depth d it presses with the penalty pressure
/// contact_stiffness_n_per_mm * d / 1 cm^2. A cut tool cuts only where its inner shape reaches
/// material and the mean pressure over the outer shape's contact is at or above cut_pressure_pa.
struct ToolSpec {
    /// Unique, non-empty; the script refers to the tool by it.
    std::string name;
    ToolShape shape = ToolShape::blade;
    /// blade, scalpel: extent along the tool's x (length), y (thickness), z (height), mm; a
    /// scalpel without size_mm is 30 x 0.5 x 8.
    Eigen::Vector3d size_mm = Eigen::Vector3d::Zero();
    /// sphere, cylinder: radius, mm.
    double radius_mm = 0.0;
    /// cylinder: length along the tool's z, mm.
    double length_mm = 0.0;
    /// mesh: the tool's surface mesh (vertices in mm), absolute; it existed when read.
    std::filesystem::path mesh;
    /// What the tool does; absent from the file: default_tool_action(shape).
    ToolAction action = default_tool_action(ToolShape::blade);
    /// cut tools: what the cut does to the material. Default per method (use_method): the
    /// branched grid removes, Is-XFEM separates (it cannot remove).
    CutMode cut_mode = CutMode::remove;
    /// The scene file said which cut_mode (else the method's default applies).
    bool cut_mode_given = false;
    /// The outer (pushing) shape is the inner (cutting) shape grown by this much, mm, in [0, 100].
    double push_margin_mm = 1.0;
    /// Penalty stiffness per cm^2 of contact, N/mm, in (0, 1e4]: a flat face of the outer shape
    /// pressed 1 mm into the object over 1 cm^2 pushes with this many newtons (pressure
    /// k * depth / 1 cm^2; the default 5 N/mm is 5e4 Pa per mm of depth).
    double contact_stiffness_n_per_mm = 5.0;
    /// cut tools: the mean contact pressure on the outer shape (total contact force over contact
    /// area), Pa, in (0, 1e9], above which the inner shape may cut.
    double cut_pressure_pa = 2e4;
    /// wet tools: how fast the water content (0..1) of the elements touched rises, per second of
    /// contact, in (0, 1e3]; the content stops at 1.
    double wet_rate_per_s = 1.0;
    /// drill tools: the burr's speed, revolutions per minute, in (0, 1e6] (surgical drills turn
    /// at 10,000 to 80,000 rpm).
    double burr_speed_rpm = 40000.0;
    /// drill tools: material removed per newton of pressing force per revolution, mm^3, in
    /// (0, 1]: the removal rate is this x force (N) x revolutions per second. The default
    /// removes 10 mm^3/s at 1 N and 50,000 rpm, the order of bone-drilling rates reported for
    /// otologic burrs.
    double drill_rate_mm3_per_n_rev = 0.012;
    /// The spring joining the tool (its proxy, held outside material it does not cut or drill) to
    /// what drives it (the script, a device), N/mm, in (0, 1e6]. Absent: a script-driven tool's
    /// is k_script_coupling_n_per_mm, a device's the device's own (contact/proxy.hpp).
    std::optional<double> coupling_stiffness_n_per_mm;
    /// Where a force-feedback device's own frame lies in the scene (`"device_frame"`): scene =
    /// origin + scale x rotation x device position. Absent: the device's origin at the tool's
    /// first script position (else above the object, as the viewer places a tool), its axes the
    /// scene's, scale 1 (haptics/framed_device.hpp).
    std::optional<DeviceFrameSpec> device_frame;
    /// Haptic subdivision at the contact (contact/contact_patch.hpp): the Loop subdivisions, 0 to
    /// 3, of the surface patch the haptic loop presses, which gives under the tool between
    /// frames as the FEM would; -1 (the default): no patch, the snapshot stays rigid between
    /// frames (docs/haptics.md says why it is not on by default yet).
    int haptic_subdivision = -1;
    /// Two-phase cutting (the sculpting paper's): while a cut tool touches the object, the object
    /// is held still and the tool marks its cut; when the cut condition is met the whole marked
    /// path is cut at once and the simulation resumes. Default false: cuts happen frame by frame.
    bool two_phase = false;
};

/// One key frame of the tool script: where a tool is, and how it is turned, at a time. Between two
/// key frames of a tool it moves in a straight line at constant speed and turns at constant angular
/// speed about one axis, the shorter way (slerp); before its first and after its last it stays.
/// io/tool_script.hpp computes the pose at any time.
struct ScriptEntry {
    /// Simulated time, s (>= 0; entries are in non-decreasing time order).
    double t_s = 0.0;
    /// The tool's name, as declared in Scene::tools.
    std::string tool;
    /// Index of that tool in Scene::tools.
    std::size_t tool_index = 0;
    /// Position of the tool's origin, world mm.
    Eigen::Vector3d position_mm = Eigen::Vector3d::Zero();
    /// Key "orientation_wxyz" ([w, x, y, z]): the rotation from the tool's frame to the world
    /// frame, a unit quaternion (the file's is normalised when read; its norm must be at least
    /// 1e-9). Default identity: the tool's axes are the world axes.
    Eigen::Quaterniond orientation = Eigen::Quaterniond::Identity();
};

/// What a run writes, and where.
struct OutputSettings {
    /// Output folder, absolute (given relative to the scene's folder; default "out").
    std::filesystem::path dir;
    /// A surface mesh is written every this many frames (>= 1).
    int mesh_every_n_frames = 10;
    /// Key "volumes": the formats the final voxels are written in, as final.<format> in rest space
    /// on the scan's grid: "vdb", "nii.gz", "nii", "nrrd", "seg.nrrd".
    std::vector<std::string> volumes;
    /// Key "vtu_every_n_frames": the finite-element mesh is written as mesh_NNNNN.vtu every this
    /// many frames, with mesh.pvd listing them for ParaView; 0: never.
    int vtu_every_n_frames = 0;
};

/// A whole scene file, validated; paths absolute.
struct Scene {
    /// The scene file's name as given (e.g. "scenes/liver.json"): every message starts with it.
    std::string source;
    /// Absolute folder the scene's relative paths were resolved against.
    std::filesystem::path folder;

    SceneObject object;
    /// Material of every voxel whose label has no entry in label_materials.
    Material default_material;
    /// Materials by voxel label (scans selected by label, or taken whole); keys the file did not
    /// set come from default_material.
    std::map<std::int32_t, Material> label_materials;
    SolverSettings solver;
    /// Gravitational acceleration in the world frame, m/s^2.
    Eigen::Vector3d gravity_m_s2{0.0, 0.0, -9.81};
    std::vector<Constraint> constraints;
    /// Static obstacles; none by default.
    std::vector<Obstacle> obstacles;
    PieceContactSettings piece_contact;
    /// External point forces, constant in time; none by default.
    std::vector<Load> loads;
    /// Initial water content by region; none by default (dry).
    std::vector<WetRegion> wet_regions;
    std::vector<ToolSpec> tools;
    /// Tool key frames in time order.
    std::vector<ScriptEntry> script;
    OutputSettings output;

    /// The material of voxels carrying `label`.
    [[nodiscard]] const Material& material(std::int32_t label) const;
    /// An error about this scene found after reading it (e.g. a constraint or load box that
    /// holds no voxel centre): "SOURCE: KEY_PATH: PROBLEM", key_path as "constraints[0].box_mm" or
    /// "loads[0].box_mm".
    [[nodiscard]] InputError error(std::string_view key_path, std::string_view problem) const;
};

/// The cut_mode a cutting tool has when the scene does not say: "remove" on the branched grid,
/// "separate" on Is-XFEM (which cannot remove material).
[[nodiscard]] CutMode default_cut_mode(SolverType type);
/// Simulates `scene` with `type` (a command line's override of solver.type): the tools whose
/// cut_mode the file left open take that method's default.
void use_method(Scene& scene, SolverType type);

/// Whether the object's surface is smoothed: the scene's "smooth_surface", else on for scans and
/// meshes simulated by the branched grid, and off for phantoms (their exact, documented shapes
/// are what tests and benchmarks compare against) and for Is-XFEM (its crack closure works on
/// the voxel surface).
[[nodiscard]] bool smooths_surface(const SceneObject& object, SolverType solver);

/// Reads and validates a scene file. Comments (// and /* */) are allowed in it. Throws
/// InputError "FILE: key.path: problem", or "FILE: line L column C: problem" for bad JSON.
[[nodiscard]] Scene load_scene(const std::filesystem::path& path);

/// Validates an already parsed scene document. Relative paths are resolved against `folder`;
/// messages start with `name_for_messages`.
[[nodiscard]] Scene parse_scene(const nlohmann::json& document, const std::filesystem::path& folder,
                                const std::string& name_for_messages);

} // namespace vox::io
