#pragma once
// Static obstacles a scene places around its object (a table, two supports, a tray): solid
// shapes the object's surface is pushed out of, with friction. Tools pass through them.
//
// Contact is the tools' penalty model (contact/penalty_contact.hpp) with the obstacle in the
// tool's place: a surface point at depth d inside the obstacle, carrying area a, is pushed out
// along the obstacle's outward normal g by f_n = k d a / (1 cm^2), k the obstacle's
// stiffness_n_per_mm. Unlike a tool's, the push follows the obstacle's normal, not the object's:
// a table pushes up under the rounded edge of an organ, not sideways.
//
// Friction is Coulomb's, regularised and lagged (as incremental potential contact lags it): a
// point sliding at tangential speed |v_t| is resisted by a viscous force -c v_t with
// c = mu |f_n| / max(|v_t|, k_stick_speed_mm_s), both f_n and |v_t| taken at the frame's start.
// Sliding, the force is mu |f_n| against the motion; nearly at rest, it is a stiff damper that
// holds the point (it creeps at most at k_stick_speed_mm_s under a tangential load equal to the
// friction limit). The solver takes the damper implicitly, as a tangential stiffness c / dt on
// the step's displacement (displacement over the step = dt v at its end), so it is stable
// however large c is.

#include "contact/penalty_contact.hpp"
#include "contact/tool_shape.hpp"

#include <Eigen/Core>
#include <Eigen/Geometry>

#include <optional>
#include <span>

namespace vox::contact {

/// Below this tangential speed friction holds a point (mm/s); see the header.
inline constexpr double k_stick_speed_mm_s = 1.0;

class Obstacle {
public:
    /// Solid on the side opposite the unit normal `normal`, through `point_mm`.
    static Obstacle plane(const Eigen::Vector3d& point_mm, const Eigen::Vector3d& normal);
    /// The solid box [lo, hi], mm (hi > lo on every axis).
    static Obstacle box(const Eigen::Vector3d& lo, const Eigen::Vector3d& hi);
    /// The inside of a closed, consistently oriented mesh, world mm. Throws InputError when it has
    /// no triangle.
    static Obstacle mesh(TriangleMesh world_mesh);

    /// Signed distance from p (world mm) to the obstacle's surface, negative inside; `gradient`,
    /// when given, receives the outward unit normal there.
    [[nodiscard]] double signed_distance(const Eigen::Vector3d& p, Eigen::Vector3d* gradient = nullptr) const noexcept;
    /// Whether some point of `box` (world mm) may lie inside the obstacle: the broad phase.
    [[nodiscard]] bool may_reach(const Eigen::AlignedBox3d& box) const;
    /// A box holding every point of the obstacle: everything, for a plane.
    [[nodiscard]] Eigen::AlignedBox3d bounds() const;
    /// A triangle mesh to draw, world mm: a plane as the square of side 2 `extent_mm` centred on
    /// the point of the plane nearest `centre_mm`, a box and a mesh as they are.
    [[nodiscard]] TriangleMesh drawing_mesh(const Eigen::Vector3d& centre_mm, double extent_mm) const;

    double friction = 0.3;            ///< Coulomb coefficient (>= 0)
    double stiffness_n_per_mm = 10.0; ///< per cm^2 of contact (> 0)

private:
    Obstacle() = default;
    std::optional<ToolShape> m_shape; ///< box and mesh: their exact distance, placed at m_origin
    Eigen::Vector3d m_origin = Eigen::Vector3d::Zero(); ///< plane: its point; box: its centre
    Eigen::Vector3d m_normal = Eigen::Vector3d::UnitZ(); ///< plane
    Eigen::AlignedBox3d m_bounds;                      ///< box and mesh
};

/// Contact of surface points (world mm, each carrying `areas[i]` mm^2 and moving at
/// `velocities_mm_s[i]`) with `obstacle` over a step of `dt_s`: the normal penalty and the
/// friction of the header, each point's stiffness along its normal and its friction's
/// tangential stiffness. Points outside are skipped. force_on_tool_n is the force on the obstacle.
[[nodiscard]] ContactResult obstacle_contact(const Obstacle& obstacle, std::span<const Eigen::Vector3d> points,
                                             std::span<const double> areas, std::span<const Eigen::Vector3d> velocities_mm_s, double dt_s);

} // namespace vox::contact
