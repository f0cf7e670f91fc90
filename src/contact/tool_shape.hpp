#pragma once
// The geometry of a tool in its own frame (millimetres): an exact signed distance (negative
// inside) and a triangle mesh. A tool is two nested shapes (Jerabkova et al. 2010, Figure 11):
// the inner one cuts, the outer one, the inner grown by a margin, pushes. Growing is exact on the
// distance: the outer shape is {p : distance(p) < margin} (a Minkowski sum with a ball), so both
// shapes come from one function.
//
// Shapes, each centred on the tool's origin:
//  - box: full extents `size` along the tool's x, y, z (a blade: length, thickness, height);
//  - scalpel: the box's profile in the x-z plane with its front (+x) end cut at 45 degrees from
//    the bottom front corner (the point) upward and back, extruded over the thickness (y); the
//    cutting edge is the bottom (-z) edge;
//  - sphere: a ball of a radius;
//  - cylinder: a solid cylinder along the tool's z (a drill's shaft or a flat-ended burr), flat
//    ends;
//  - mesh: any closed, consistently oriented triangle mesh (distance to the nearest triangle,
//    sign by the generalised winding number).

#include <Eigen/Core>
#include <Eigen/Geometry>

#include <cstdint>
#include <cmath>
#include <vector>

namespace vox::contact {

struct TriangleMesh {
    std::vector<Eigen::Vector3d> positions;  ///< mm
    std::vector<Eigen::Vector3i> triangles; ///< counter-clockwise seen from outside
};

class ToolShape {
public:
    enum class Kind { box, scalpel, sphere, cylinder, mesh };

    /// `size`: full extents along x, y, z, mm (each > 0).
    static ToolShape box(const Eigen::Vector3d& size);
    /// `size`: length (x), thickness (y), height (z), mm (each > 0).
    static ToolShape scalpel(const Eigen::Vector3d& size);
    static ToolShape sphere(double radius);
    /// Radius across, length along the tool's z, mm (each > 0); centred on the origin.
    static ToolShape cylinder(double radius, double length);
    /// A closed triangle mesh in the tool's frame, mm. Throws InputError when it has no triangle.
    static ToolShape from_mesh(TriangleMesh mesh);

    [[nodiscard]] Kind kind() const { return m_kind; }

    /// Signed distance from p (tool frame, mm) to the surface: negative inside. `gradient`, when
    /// given, receives the unit direction in which the distance grows fastest (the outward normal
    /// of the nearest surface point).
    [[nodiscard]] double signed_distance(const Eigen::Vector3d& p, Eigen::Vector3d* gradient = nullptr) const noexcept;

    /// How far outside the shape grown by `margin` each end of a segment `length_mm` long can be
    /// when the segment reaches into it, mm: sqrt(rho^2 + L^2) - rho, with rho the margin plus the
    /// radius the shape is itself rounded with (a sphere's; the others' edges are sharp). The
    /// grown shape is a set grown by rho, and the segment's nearest point to the set's nearest
    /// point c lies within rho of c, at a right angle: each end is within sqrt(rho^2 + L^2) of c.
    /// A finer cut than the distance's Lipschitz bound (L) for the segments a contact's rim holds.
    [[nodiscard]] double reach_band_mm(double margin, double length_mm) const noexcept
    {
        const double rho = margin + (m_kind == Kind::sphere ? m_radius : 0.0);
        return std::sqrt(rho * rho + length_mm * length_mm) - rho;
    }

    /// The area (mm^2) of the shape grown by `margin` as seen along `along` (tool frame): what
    /// the contact across that direction can cover at most. Exact for the analytic shapes (a
    /// cylinder's round outline taken as a circumscribed 48-gon); a mesh tool's is its vertices'
    /// hull's, or infinity beyond 256 vertices. Never allocates.
    [[nodiscard]] double shadow_area(const Eigen::Vector3d& along, double margin = 0.0) const noexcept;

    /// Bounds of the shape grown by `margin` (mm), tool frame.
    [[nodiscard]] Eigen::AlignedBox3d bounds(double margin = 0.0) const;

    /// Box and scalpel: their x-z profile grown by `margin` (each edge moved out, corners not
    /// rounded), counter-clockwise (x right, z up); empty for other shapes.
    [[nodiscard]] std::vector<Eigen::Vector2d> profile(double margin = 0.0) const;

    /// A triangle mesh of the shape grown by `margin`, for pictures and continuous collision:
    /// boxes and scalpels keep their flat faces (each face moved out by the margin, corners not
    /// rounded), spheres are subdivided icosahedra (`detail` subdivisions) of radius + margin,
    /// meshes move each vertex out by the margin along its normal.
    [[nodiscard]] TriangleMesh mesh(double margin = 0.0, int detail = 2) const;

private:
    ToolShape() = default;
    [[nodiscard]] double prism_distance(const Eigen::Vector3d& p, Eigen::Vector3d* gradient) const noexcept;
    [[nodiscard]] double mesh_distance(const Eigen::Vector3d& p, Eigen::Vector3d* gradient) const noexcept;

    Kind m_kind = Kind::box;
    Eigen::Vector3d m_size = Eigen::Vector3d::Zero();
    double m_radius = 0.0;
    double m_length = 0.0; ///< cylinder
    /// box, scalpel: the convex profile in the x-z plane, counter-clockwise (x right, z up).
    std::vector<Eigen::Vector2d> m_profile;
    /// Its edges as the distance needs them, worked out once (set_profile): the distance is
    /// taken for every surface point near the tool at every 1 kHz tick.
    struct ProfileEdge {
        Eigen::Vector2d a, e, normal; ///< start, edge vector, outward unit normal
        double inverse_length2 = 0.0; ///< 1 / |e|^2
    };
    std::vector<ProfileEdge> m_edges;
    void set_profile(std::vector<Eigen::Vector2d> profile);
    TriangleMesh m_mesh; ///< mesh tools
    /// Points whose convex hull is the inner shape (a sphere's: none): its shadow's outline.
    std::vector<Eigen::Vector3d> m_outline;
    void set_outline();
    Eigen::AlignedBox3d m_bounds;
};

/// A tool shape placed in the world: world = position + orientation * tool frame (mm).
struct PlacedShape {
    const ToolShape* shape = nullptr;
    Eigen::Vector3d position = Eigen::Vector3d::Zero();
    Eigen::Quaterniond orientation = Eigen::Quaterniond::Identity();

    /// Signed distance of a world point (mm); `gradient` in world frame.
    [[nodiscard]] double signed_distance(const Eigen::Vector3d& world, Eigen::Vector3d* gradient = nullptr) const noexcept;
    /// World-axis box holding the shape grown by `margin`.
    [[nodiscard]] Eigen::AlignedBox3d world_bounds(double margin = 0.0) const;
};

} // namespace vox::contact
