#pragma once
// Contact of an object's surface with itself: pieces cut free resting on or falling onto the rest,
// the two walls of a cut pressed together, a fold closing on itself. The tools' penalty model
// (contact/penalty_contact.hpp), vertex against face and edge under edge (EdgeContact below): a
// surface vertex that has gone behind a facing triangle of the surface is pushed out along the
// triangle's normal by
//     f = k d a / (1 cm^2),
// d the depth, a half the vertex's area as it faces the triangle (both sides' vertices press, so
// two flat faces pressed together are pushed apart by k d A over their area A, as a tool's face
// would be), and the
// triangle's three corners are pushed back with the opposite force shared by the barycentric
// weights of the point the vertex presses: equal and opposite, so a contact never moves the
// pair's centre of mass. The force is taken at the step's end, implicitly: f = k a d at the
// step's start, d the depth (negative: apart), plus the stiffness k a times the relative motion
// along the normal, so that it is k a times the depth where the step ends. The solver finds that
// end, so the penetration interval the tools' penalty integrates over (their path is known) is
// here the step itself, and backward Euler's end value is what keeps a resting piece at rest.
// Integrated as the tools' (the mean over the step, linearised about a predicted end) it is the
// trapezoidal rule, which rings on a stiff contact: a block landing on another bounced every
// other frame by its own depth and never settled. A vertex touching (apart by less than
// `skin_mm`) or predicted (start plus dt times the velocities) to reach the face during the step
// is a contact too, with its start force zero or negative: the step stops it at the surface
// instead of letting it sink a step's fall into it and throwing it back out, and a piece resting
// there stays caught while its weight pulls it in. The solver lets go of the contacts that would
// pull at the step's end (fem/pair_contact.hpp): two sides that part are not held together.
// Only those already touching or coming together are caught, so nothing attracts two walls that
// merely lie near each other (a blade between them).
//
// Which vertex and triangle may touch: not the triangle's own corners; only a triangle facing the
// vertex (its normal against the vertex's, more than 105 degrees apart), so a voxel surface's
// corners and steps never catch themselves; and never through material: a vertex that lies
// behind the triangle in the rest shape already (more than `rest_tolerance_mm`, where the rest
// triangle covers it) is the far side of the object, not a contact. The two walls of a cut lie
// on each other at rest (distance 0) and pass the test; the top and bottom faces of a thin plate
// do not. A vertex deeper than max_depth_mm is taken to have gone through (or to be the other
// side of a thin part), not pressed.

#include <Eigen/Core>

#include <array>
#include <cstdint>
#include <vector>

namespace vox::contact {

struct PieceContactParameters {
    double stiffness_n_per_mm = 10.0;   ///< per cm^2 of contact (> 0)
    double max_depth_mm = 1.0;          ///< deeper is not a contact (> 0)
    double approach_mm = 0.9;           ///< broad phase: elements nearer than this are tested
    double skin_mm = 0.02;              ///< apart by less than this is touching
    double rest_tolerance_mm = 0.5;     ///< behind the rest triangle by more: through material
};

/// The surface near where it may touch itself, world mm: each vertex at the step's start, at its
/// predicted end and at rest, and the triangles among the vertices. Vertices flagged `presses`
/// have all their triangles in the patch and press faces; the others (its rim) are only corners.
struct SurfacePatch {
    std::vector<Eigen::Vector3d> start_mm, end_mm, rest_mm;
    std::vector<unsigned char> presses;
    std::vector<Eigen::Vector3i> triangles;
    /// Flips every triangle's corner order's normal (a mirroring scan's inward-ordered slots).
    double outward_sign = 1.0;
};

/// A vertex pressing a triangle of the same surface.
struct FaceContact {
    std::uint32_t vertex = 0;
    std::uint32_t triangle = 0;
    /// The pressed point of the triangle: its corners' weights (sum 1), at the step's start.
    std::array<double, 3> weights{};
    Eigen::Vector3d normal = Eigen::Vector3d::Zero(); ///< the triangle's outward normal: the vertex is pushed along it
    double depth_mm = 0.0;              ///< at the step's start; negative: apart
    double force_n = 0.0;               ///< k a depth: on the vertex along normal, the triangle takes minus it
    double stiffness_n_per_mm = 0.0;    ///< d force / d depth (k a)
    double area_mm2 = 0.0;
};

/// An edge of the surface passing under another edge of it, neither's ends in: two ridges pressed
/// across each other (a cut piece's edge lying across a wall's edge), which no vertex against a
/// face sees. The pressing edge enters the surface through one of the two triangles beside the
/// pressed edge and leaves through the other, at the step's start (or, for one arriving, at its
/// predicted end). The points are the two edges' nearest points; the normal is along the two
/// edges' cross product, turned out of the pressed edge's side; the area is the share of the
/// pressing edge that is in times a sixth of its ends' areas (a vertex has about three edges of its
/// own), as for a tool's edge (contact/penalty_contact.hpp, the Is-XFEM paper's equation 19). Two
/// edges under each other count once.
struct EdgeContact {
    std::array<std::uint32_t, 2> edge{};    ///< the pressing edge's ends (patch vertices)
    std::array<std::uint32_t, 2> pressed{}; ///< the pressed edge's ends
    double s = 0.0;                         ///< its point: (1 - s) edge[0] + s edge[1], at the step's start
    double t = 0.0;                         ///< the pressed point: (1 - t) pressed[0] + t pressed[1]
    Eigen::Vector3d normal = Eigen::Vector3d::Zero(); ///< out of the pressed side: the pressing point is pushed along it
    double depth_mm = 0.0;                  ///< at the step's start; negative: apart
    double force_n = 0.0;                   ///< k a depth, on the pressing point along normal
    double stiffness_n_per_mm = 0.0;        ///< d force / d depth (k a)
    double area_mm2 = 0.0;
};

/// Every edge of `patch` whose ends both press (`presses`) passing under an edge of it, each pair
/// of edges once; the same parameters and tests as face_contacts (facing sides, not through
/// material at rest, no deeper than max_depth_mm, touching or predicted to arrive). Edges with other
/// than two triangles in the patch (its rim) are neither. Throws std::invalid_argument as
/// face_contacts does.
[[nodiscard]] std::vector<EdgeContact> edge_contacts(const SurfacePatch& patch, const PieceContactParameters& parameters);

/// Every vertex of `patch` pressing a triangle of it (each vertex its deepest). Triangles are
/// found through a uniform grid over their boxes, so the cost grows with the patch, not with the
/// pairs. Throws std::invalid_argument when the patch's arrays differ in length.
[[nodiscard]] std::vector<FaceContact> face_contacts(const SurfacePatch& patch, const PieceContactParameters& parameters);

struct SurfaceContacts {
    std::vector<FaceContact> faces;
    std::vector<EdgeContact> edges;
};

/// Both, with the triangles measured once (their normals, areas and grid), and edges searched only
/// where they may pass under another: those with an end that the vertex phase saw within
/// max_depth_mm of a triangle turned more than 90 degrees from its normal, or longer than twice
/// max_depth_mm. An edge that passes under another enters and leaves the surface there, one of its
/// ends within half its length of where, so an edge no longer than twice the depth has an end
/// within the depth of a triangle it crosses. On a whole surface most edges are near no other part
/// of it, and searching every edge cost twice the vertex phase (an Is-XFEM bracket: 15 ms against
/// 7 a frame). The same contacts as face_contacts and edge_contacts.
[[nodiscard]] SurfaceContacts surface_contacts(const SurfacePatch& patch, const PieceContactParameters& parameters);

} // namespace vox::contact
