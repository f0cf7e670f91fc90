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
// Friction is Coulomb's, as a stick-slip spring (the penalty friction of haptic rendering): a
// point that comes into contact is tied to an anchor where it touched by a spring across the
// normal. While the spring pulls with at most mu |f_n| the point sticks; beyond, it slips: the
// anchor is dragged behind it at the distance where the spring pulls with exactly mu |f_n|. A
// sticking point gives k_stick_give_mm before it slips (more only when pressed in deeper than
// k_stick_give_mm / mu: the spring is never stiffer than the normal penalty), and under a smaller
// load does not move at all: no creep. The solver takes the spring implicitly (stick: its stiffness across
// the normal; slip: across the normal and the slip, the derivative of a force of fixed size), so
// a point that stops sliding cannot be thrown back: it lands on its spring. One linear solve a
// step cannot switch between stick and slip within the step, so the spring is made soft enough
// that the step's expected slide (the point's speed at the step's start times dt) stretches it
// to mu |f_n| at most: the step neither holds a sliding point much beyond Coulomb's force nor
// lets it go much before.

#include "contact/penalty_contact.hpp"
#include "contact/tool_shape.hpp"

#include <Eigen/Core>
#include <Eigen/Geometry>

#include <cstdint>
#include <optional>
#include <unordered_map>
#include <span>

namespace vox::contact {

/// Where each surface point touching an obstacle is anchored (world mm), by the point's identity
/// (a method's key of a material point, the same from frame to frame): friction's memory.
using FrictionAnchors = std::unordered_map<std::uint64_t, Eigen::Vector3d>;

/// How far a sticking point gives before it slips, mm (see the header).
inline constexpr double k_stick_give_mm = 0.01;

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

/// Contact of surface points (world mm, each carrying `areas[i]` mm^2, moving at
/// `velocities_mm_s[i]`, identified by `keys[i]`) with `obstacle` for a step of `dt_s`: the
/// normal penalty and the friction of the header, each point's force and stiffness. A point
/// outside that touches (nearer than `skin_mm`) or whose end of the step moving freely,
/// `ends_mm[i]` (its velocity and gravity; none given: not looked at), is inside is a contact too, with a normal force k d a that is zero or pulls (d <= 0) and no friction: the
/// solver takes the normal force at the step's end (fem/pair_contact.hpp) and lets it go if it
/// would still pull there, so an arriving point is stopped at the surface instead of sinking a
/// step's fall into it and being thrown back out (a lagged penalty bounces a resting piece by
/// that much every other step, for ever). Such a point waits out of the solve until a solve ends
/// with it pressed in (fem::PairContact::waiting): a piece at rest on a table has hundreds of
/// points within gravity's look-ahead (g dt^2) of it, and each pulling in the first solve would
/// drag it down. `anchors` holds the anchors of the last call and
/// receives this call's (points no longer pressed in let go). force_on_tool_n is the force on
/// the obstacle at the points' positions, friction included (arriving points add none); area_mm2
/// the area of the points inside.
[[nodiscard]] ContactResult obstacle_contact(const Obstacle& obstacle, std::span<const Eigen::Vector3d> points,
                                             std::span<const double> areas, std::span<const Eigen::Vector3d> velocities_mm_s,
                                             double dt_s, std::span<const std::uint64_t> keys, FrictionAnchors& anchors,
                                             double skin_mm = 0.0, std::span<const Eigen::Vector3d> ends_mm = {});

} // namespace vox::contact
