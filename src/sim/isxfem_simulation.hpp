#pragma once
// A scene simulated with the Is-XFEM solver (`"solver": {"type": "isxfem"}`): the tetrahedra of the
// scene's object at the chosen level (isxfem/grid_tets.hpp: the branched elements split in six,
// so the supports catch the same nodes as the branched-grid solver's), the scene's gravity,
// constraints and solver settings, blade cuts, and the object's surface embedded in the
// tetrahedra by barycentric coordinates (each vertex on its side of any cut through its
// tetrahedron), closed along the cuts (isxfem/cut_closure.hpp): what tools touch, the haptic
// loop samples and runs export.

#include "contact/obstacle.hpp"
#include "contact/penalty_contact.hpp"
#include "contact/piece_contact.hpp"
#include "contact/surface_points.hpp"
#include "fem/pair_contact.hpp"
#include "io/scene.hpp"
#include "isxfem/cut_closure.hpp"
#include "isxfem/grid_tets.hpp"
#include "isxfem/xfem_solver.hpp"
#include "surface/embedded_surface.hpp"

#include <memory>

namespace vox::sim {

class IsxfemSimulation {
public:
    /// Throws the scene's InputError when a constraint or load box holds no voxel centre.
    IsxfemSimulation(const io::Scene& scene, const grid::BranchedGrid& grid, int level);
    ~IsxfemSimulation();
    /// The pieces no constraint reached, held in place ("unheld_pieces": "hold").
    [[nodiscard]] std::size_t held_piece_count() const { return m_held_pieces; }
    /// Hexahedral cells (of the level the tetrahedra come from) holding rigid material, held in place.
    [[nodiscard]] std::size_t rigid_element_count() const { return m_rigid_elements; }

    [[nodiscard]] const isxfem::XfemModel& model() const { return *m_model; }
    [[nodiscard]] isxfem::XfemSolver& solver() { return *m_solver; }
    [[nodiscard]] const isxfem::XfemSolver& solver() const { return *m_solver; }
    [[nodiscard]] std::size_t tet_count() const { return m_model->elements().size(); }

    /// Cuts along a blade's swept surface (rest space, m) where it goes through tetrahedra whole;
    /// its patches from `new_from` on are new. `extend`: the id of the cut this continues (-1: a
    /// new one).
    isxfem::CutReport cut(const isxfem::CutSurface& surface, std::size_t new_from, int extend);

    /// One call of cut(), as a session journal keeps it: the patches the surface gained since the
    /// cut it extends last saw it (all of them for a new cut), where the new ones begin, and the cut
    /// it extends. Every call is kept, even one that cut nothing: it moves the extended cut's surface on.
    struct CutCall {
        int extend = -1;
        std::size_t new_from = 0;
        std::vector<isxfem::CutPatch> patches;
    };
    [[nodiscard]] const std::vector<CutCall>& cut_log() const { return m_cut_log; }
    /// Makes a logged call again on this model: the extended cut's surface plus the call's
    /// patches, cut as it was. Throws InputError for a call that does not fit the model.
    isxfem::CutReport replay(const CutCall& call);

    /// The deformed surface, world mm, closed along the cuts: triangles are split where a cut's
    /// crack crosses them (each piece moving with its side) and each crack is filled on both
    /// sides, through the object or, for a slit, up to its front (isxfem/cut_closure.hpp).
    [[nodiscard]] surface::SurfaceMesh surface_mesh() const;
    /// What each vertex of surface_mesh() is, for pictures: the object's surface, made by a cut
    /// (split or crack face), or in or beside a tetrahedron whose pieces the cuts could not all
    /// separate (two cuts crossing inside it, or a further cut left out there).
    enum class Mark : unsigned char { surface, cut, coupled };
    [[nodiscard]] std::vector<Mark> surface_marks() const;
    /// How many vertices surface_mesh() has (without placing them).
    [[nodiscard]] std::size_t surface_vertex_count() const;
    /// What closing the surface along the cuts made, and what it had to leave open.
    [[nodiscard]] isxfem::ClosureCounts closure_counts() const;
    /// Displacement (m) of every used surface vertex, in the order of surface_mesh()'s vertices.
    [[nodiscard]] std::vector<Eigen::Vector3d> surface_displacements() const;
    /// The identity (surface::SurfaceVertex::key) of each of those vertices, the same as in a
    /// branched-grid simulation of the same scene and level.
    [[nodiscard]] std::vector<std::uint64_t> surface_keys() const;

    /// A tool pressed against the deformed, closed surface (contact::penalty_contact on its
    /// vertices, each carrying a third of its triangles' area and their area-weighted normal),
    /// and the contact's forces as point loads at the vertices' material points for the solver.
    /// With `from`, the tool's pose at the previous frame: the penalty is integrated over the
    /// move (continuous penalty). With `closed_walls_mm` > 0, crack faces whose walls are still
    /// closer together than that (a blade's thickness) are left out: walls that lie on each other
    /// close on a blade from both sides at once, which only stiffens the solve and shakes a haptic
    /// tool; walls that have opened (a piece fallen away) are touched like the rest.
    struct Touch {
        contact::ContactResult contact;
        std::vector<isxfem::PointLoad> loads;
    };
    [[nodiscard]] Touch touch(const contact::PlacedShape& tool, const contact::ContactParameters& parameters,
                              const contact::PlacedShape* from = nullptr, double closed_walls_mm = 0.0) const;

    /// The closed surface pressed against a static obstacle for a step of `dt_s`
    /// (contact::obstacle_contact; `anchors` its friction's, by material point: rest position and
    /// side; points nearer than `skin_mm` or arriving within the step are caught, of those within
    /// `approach_mm` of the obstacle's bounds; those apart wait: fem::PairContact::waiting): the push along its normal as one-sided pair
    /// contacts (fem/pair_contact.hpp), the friction as point loads.
    struct ObstacleTouch {
        contact::ContactResult contact;
        std::vector<fem::PairContact> pairs;
        std::vector<isxfem::PointLoad> loads;
    };
    [[nodiscard]] ObstacleTouch touch_obstacle(const contact::Obstacle& obstacle, double dt_s, contact::FrictionAnchors& anchors,
                                               double skin_mm, double approach_mm) const;

    /// The closed surface pressed against itself over a step of `dt_s` (contact/piece_contact.hpp:
    /// pieces on pieces, the walls of a crack): the vertices that come near parts of the surface
    /// material does not join, and those beside a crack, press (the broad phase: the .cpp); each
    /// contact is a pair contact on the dof blocks of its two material points (fem/pair_contact.hpp).
    struct PieceTouch {
        std::vector<contact::FaceContact> faces;
        std::vector<contact::EdgeContact> edges;
        std::vector<fem::PairContact> pairs;
        std::size_t vertices = 0; ///< surface vertices the broad phase passed on
    };
    [[nodiscard]] PieceTouch touch_pieces(double dt_s, const contact::PieceContactParameters& parameters) const;

    /// Fills `out` with the points of the deformed, closed surface within `box` (world mm), each
    /// with its area and outward normal, and the triangles among them: the snapshot the haptic
    /// thread touches (at most out.capacity() points; out.truncated says when more were near),
    /// without the crack faces whose walls are closer than `closed_walls_mm` (as touch()).
    void sample_surface(const Eigen::AlignedBox3d& box, contact::SurfacePoints& out, double closed_walls_mm = 0.0) const;

    /// The side (of its cut; 0 when uncut) of the material point with barycentric coordinates
    /// `bary` in tetrahedron `tet`.
    [[nodiscard]] int side_of(std::size_t tet, const std::array<double, 4>& bary) const;

    /// The mean displacement (mm) of the nodes of the tetrahedra whose deformed box meets `box`
    /// (world mm): how far the material there has moved from rest.
    [[nodiscard]] Eigen::Vector3d mean_displacement_mm(const Eigen::AlignedBox3d& box) const;

    /// The cut model and the solver's state at one moment (the viewer's undo).
    struct State {
        isxfem::XfemModel model;
        std::vector<Eigen::Vector3d> x, v;
        std::vector<CutCall> cut_log;
    };
    [[nodiscard]] State state() const;
    /// Back to `s`: the model's cuts, a solver built anew on it, positions and velocities.
    void restore(const State& s);

private:
    /// The solver on m_model with the scene's options, preconditioner, gravity and supports.
    void make_solver();
    struct NearSurface;
    [[nodiscard]] NearSurface near_surface(const Eigen::AlignedBox3d& box, double closed_walls_mm) const;
    /// How far a point moving at `velocity_mm_s` goes in a step of dt_s moving freely (gravity
    /// too: a piece at rest on a table falls g dt^2 into it in a step), mm; what contact looks
    /// ahead to (held points are looked at as if free: a contact more, tested and let go).
    [[nodiscard]] Eigen::Vector3d free_step_mm(const Eigen::Vector3d& velocity_mm_s, double dt_s) const;
    /// Adds `weight` times material point v's weights on its tetrahedron's blocks (on its side of
    /// the cuts) to `terms`: a point as a pair contact's side.
    void add_point_terms(const isxfem::SurfacePoint& v, double weight, std::vector<fem::BlockWeight>& terms) const;
    /// The closed surface's vertices (material points) and triangles, kept until the next cut.
    void refresh_closed_surface() const;

    const grid::BranchedGrid& m_grid;
    isxfem::XfemOptions m_options;
    bool m_factor = true; ///< the warped factor, else Jacobi
    Eigen::Vector3d m_gravity = Eigen::Vector3d::Zero();
    std::vector<std::pair<std::uint32_t, unsigned>> m_fixed; ///< supported node, held axes (1 x, 2 y, 4 z)
    std::size_t m_held_pieces = 0; ///< pieces no constraint reached, held ("unheld_pieces": "hold")
    std::size_t m_rigid_elements = 0;
    std::unique_ptr<isxfem::XfemModel> m_model;
    std::unique_ptr<isxfem::XfemSolver> m_solver;
    std::unique_ptr<isxfem::CutClosure> m_closure;
    std::unique_ptr<surface::EmbeddedSurface> m_surface;
    struct Embedded {
        std::size_t tet = 0;
        std::array<double, 4> bary{};
        Eigen::Vector3d rest_m = Eigen::Vector3d::Zero();
        std::uint64_t key = 0;
    };
    std::vector<Embedded> m_vertices; ///< per used surface vertex, in mesh order
    surface::SurfaceMesh m_rest;      ///< the surface at rest: its triangles and labels
    mutable std::vector<isxfem::SurfacePoint> m_closed_vertices; ///< the closed surface as of the model's revision
    mutable std::vector<Eigen::Vector3i> m_closed_triangles;
    mutable std::vector<std::int32_t> m_closed_crack; ///< per closed triangle: the cut whose crack face it is, or -1
    mutable isxfem::ClosureCounts m_closure_counts;
    mutable std::size_t m_closed_revision = 0;
    /// The closed surface's vertices grouped by cells at rest and by connected part (piece) for
    /// touch_pieces' broad phase, as of a revision of the model: each group's cell, part and
    /// whether it holds a vertex of a cut tetrahedron.
    struct ContactGroups {
        std::size_t revision = ~std::size_t{0};
        double cell_mm = 0.0;
        std::vector<std::uint32_t> of_vertex;
        std::vector<Eigen::Array3i> cell;
        std::vector<std::uint32_t> part;
        std::vector<unsigned char> holds_cut;
    };
    mutable ContactGroups m_contact_groups;
    void refresh_contact_groups(double cell_mm) const;
    std::vector<CutCall> m_cut_log;
};

} // namespace vox::sim
