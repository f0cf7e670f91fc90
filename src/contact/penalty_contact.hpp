#pragma once
// Discrete penalty contact between a tool and points of the object's surface: the one contact
// model behind pushing, the cut decision and (later) the forces the user feels.
//
// The pushing shape is the tool's inner (cutting) shape grown by `margin_mm`. A surface point at
// depth d inside it, carrying surface area a, is pushed into the object, along minus its outward
// surface normal n, by
//     f = -k d a n / (1 cm^2),
// k the scene's contact_stiffness_n_per_mm: a flat face pressed 1 mm into the object over 1 cm^2
// pushes with k newtons, whatever the mesh resolution. The contact pressure is the mean over the
// part of the contact that carries the load, sum |f| / sum a over the points whose force points
// within 60 degrees of the net force, that area taken at most as large as the pushing shape's
// shadow across the net force (a blade narrower than the points' spacing cannot press over the
// area of two rows of points): what decides a cut. A broad tool spreads its force over a
// large area, a sharp one concentrates it; the walls of a slit rubbing a blade's sides carry no
// load and do not dilute the pressure at its edge. The force follows the object's normal, not the tool's:
// once a thin blade is inside the material the nearest tool face says nothing about which side a
// point is on, while the two walls of a slit face opposite ways and are pushed apart.

#include "contact/surface_points.hpp"
#include "contact/tool_shape.hpp"

#include <Eigen/Core>

#include <cstdint>
#include <span>
#include <vector>

namespace vox::contact {

struct ContactParameters {
    double margin_mm = 1.0;                 ///< outer shape = inner grown by this, mm (>= 0)
    double stiffness_n_per_mm = 5.0;        ///< per cm^2 of contact (> 0)
};

struct PointContact {
    std::uint32_t point = 0;                ///< index into the points given
    double depth_mm = 0.0;                  ///< inside the outer shape, > 0 (an obstacle's arriving point: <= 0)
    Eigen::Vector3d normal = Eigen::Vector3d::Zero(); ///< direction the point is pushed (unit), world
    Eigen::Vector3d force_n = Eigen::Vector3d::Zero(); ///< on the surface point
    /// d |force| / d depth. The solver takes the contact's stiffness as this times normal
    /// normal^T: the exact derivative when the tool's surface faces the object's (a flat face, a
    /// blade's edge head-on), a symmetric positive semidefinite stand-in otherwise (stable, slightly
    /// off in direction for a sphere touching at a slant).
    double stiffness_n_per_mm = 0.0;
    /// Friction's stiffness across the normal, N/mm (obstacles: contact/obstacle.hpp; tools have
    /// none): symmetric, positive semidefinite.
    Eigen::Matrix3d friction_stiffness_n_per_mm = Eigen::Matrix3d::Zero();
    bool inside_inner = false;              ///< the point is inside the inner (cutting) shape too
    double area_mm2 = 0.0;                  ///< the surface area this contact stands for
    /// The force along the normal (an obstacle's arriving point: <= 0) and across it (friction).
    [[nodiscard]] double normal_force_n() const { return force_n.dot(normal); }
    [[nodiscard]] Eigen::Vector3d across_force_n() const { return force_n - normal_force_n() * normal; }
    /// The whole stiffness, N/mm: along the normal and across it (friction).
    [[nodiscard]] Eigen::Matrix3d stiffness_matrix_n_per_mm() const
    {
        return stiffness_n_per_mm * normal * normal.transpose() + friction_stiffness_n_per_mm;
    }
};

struct ContactResult {
    std::vector<PointContact> points;
    Eigen::Vector3d force_on_tool_n = Eigen::Vector3d::Zero();       ///< the reaction: minus the sum of the point forces
    Eigen::Vector3d torque_on_tool_n_mm = Eigen::Vector3d::Zero();   ///< about the tool's origin
    double area_mm2 = 0.0;                   ///< surface area in contact
    double load_area_mm2 = 0.0;              ///< the part of it that carries the load (at most the shape's shadow)
    double pressure_pa = 0.0;                ///< sum |f| / area over the load-carrying part (0 without contact)
    [[nodiscard]] bool inner_reaches_surface() const
    {
        for (const PointContact& p : points)
            if (p.inside_inner) return true;
        return false;
    }
};

/// The totals of a contact, without the per-point list: what the 1 kHz loop needs.
struct ContactTotals {
    Eigen::Vector3d force_on_tool_n = Eigen::Vector3d::Zero();
    Eigen::Vector3d torque_on_tool_n_mm = Eigen::Vector3d::Zero();
    /// -d force_on_tool / d tool position (N/mm): sum of each point's stiffness times
    /// normal normal^T, for a tool that moves without turning.
    Eigen::Matrix3d stiffness_n_per_mm = Eigen::Matrix3d::Zero();
    double area_mm2 = 0.0;
    double load_area_mm2 = 0.0;
    double pressure_pa = 0.0;
    bool inner_reaches_surface = false;
};

/// The same model as penalty_contact over the first `points.count` points and their triangles
/// (edges included); never allocates,
/// locks or throws (the haptic loop calls it). The pressure (and load area) take a second pass
/// over the points and are computed only `with_pressure` (the force and stiffness do not need it).
/// `distance`, when given (at least points.count long), receives each point's signed distance to
/// the tool's inner shape where it was measured (points within the pushing shape's box), else
/// +infinity: the continuous check of the same tick reuses them.
[[nodiscard]] ContactTotals penalty_totals(const PlacedShape& tool, const ContactParameters& parameters, const SurfacePoints& points,
                                           bool with_pressure = true, std::span<double> distance = {}) noexcept;

/// penalty_totals' edges alone, added to `out`: for a caller that has the points' part already
/// (the contact patch, from its linearised contact). `distance` as penalty_totals fills it (the
/// points' distances where measured, else +infinity); ends not measured are measured and kept.
void add_edge_totals(const PlacedShape& tool, const ContactParameters& parameters, const SurfacePoints& points, std::span<double> distance,
                     ContactTotals& out) noexcept;

/// Measures a snapshot's slack against `tool` where it is now, pushing with margin `margin_mm`
/// (SurfacePoints::slack_pose; after index()), in the simulation thread: per point and edge, how
/// far the tool may move before it can take part in penalty_totals' contact, so that the 1 kHz
/// loop's ticks on this snapshot leave it out until then. Leaving out changes nothing the ticks
/// compute.
void measure_slack(const PlacedShape& tool, double margin_mm, SurfacePoints& points);

/// Contact of `tool` (its inner shape, placed in the world) with surface points (world mm), each
/// carrying `areas[i]` mm^2 of surface with outward unit normal `normals[i]` (a zero normal: the
/// point is pushed along the tool's outward normal instead). Points outside the outer shape are skipped.
///
/// With `from`, the tool's pose at the start of the step (it moved from there to `tool` over the
/// step), the penalty is integrated over each point's penetration interval instead (Tang, Manocha,
/// Otaduy and Tong 2012, continuous penalty forces): the depth varies linearly between its values
/// at the two poses, and a point's force is its mean over the step, so a tool that arrives between
/// two steps pushes for the part of the step it was in contact, not as if it had been there all
/// along; the force rises with the time in contact instead of jumping. A point inside at either
/// pose counts. The stiffness is scaled by the share of the step spent inside.
///
/// With `triangles` (the surface's triangles among the points), edges are pressed too (the
/// Is-XFEM sculpting paper's edge-edge penalty, its equation 19): an edge whose two ends are
/// outside the pushing shape at both poses but whose middle reaches in, as where a thin blade's
/// edge lies across a face between two vertices, is pushed at its deepest point with the same
/// penalty over the area it stands for (a third of its ends' mean area times the share of its
/// length inside); its force and stiffness go to its two ends as the point's position does (two
/// PointContacts, one per end), its reaction and torque to the tool at the point.
[[nodiscard]] ContactResult penalty_contact(const PlacedShape& tool, const ContactParameters& parameters,
                                            std::span<const Eigen::Vector3d> points, std::span<const double> areas,
                                            std::span<const Eigen::Vector3d> normals, const PlacedShape* from = nullptr,
                                            std::span<const Eigen::Vector3i> triangles = {});

/// The mean over a step of a penetration depth going linearly from d0 to d1 (negative: outside),
/// counting only the part inside; `inside` receives the share of the step spent inside.
[[nodiscard]] double mean_penetration(double d0, double d1, double& inside) noexcept;

} // namespace vox::contact
