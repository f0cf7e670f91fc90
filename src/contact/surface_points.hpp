#pragma once
// Points of the object's surface with their area and outward normal, world mm, and the triangles
// between them: what the haptic thread touches. The simulation thread fills one (the surface near
// the tool, with a box tree over its triangles; the triangle list and tree grow there as needed)
// and publishes it; the haptic thread only reads it, so it never allocates.

#include "contact/mesh_ccd.hpp"
#include "contact/tool_shape.hpp"

#include <Eigen/Core>
#include <Eigen/Geometry>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstddef>
#include <span>
#include <vector>

namespace vox::contact {

/// The edges of `triangles`, each once (smaller index first), whether two triangles share it or
/// one has it on the border of a patch.
[[nodiscard]] inline std::vector<Eigen::Vector2i> surface_edges(std::span<const Eigen::Vector3i> triangles)
{
    std::vector<Eigen::Vector2i> out;
    out.reserve(3 * triangles.size());
    for (const Eigen::Vector3i& t : triangles)
        for (int k = 0; k < 3; ++k) out.emplace_back(std::min(t[k], t[(k + 1) % 3]), std::max(t[k], t[(k + 1) % 3]));
    const auto before = [](const Eigen::Vector2i& a, const Eigen::Vector2i& b) { return a[0] < b[0] || (a[0] == b[0] && a[1] < b[1]); };
    std::sort(out.begin(), out.end(), before);
    out.erase(std::unique(out.begin(), out.end()), out.end());
    return out;
}

/// A uniform grid over a snapshot's points, so that the haptic loop visits only the points and
/// edges near the tool rather than the whole snapshot (a knife's snapshot on a block it has cut
/// again and again holds thousands of crack-wall points, a few hundred of them near the blade):
/// per cell, the points in it and the edges whose middle is in it (their ends, in cell order, so
/// that a tick reads them in sequence).
struct PointGrid {
    double cell_mm = 0.0; ///< 0: no grid, every point and edge is visited
    Eigen::Vector3d origin = Eigen::Vector3d::Zero();
    Eigen::Vector3i cells = Eigen::Vector3i::Zero();
    /// Per cell (and one more), where its points begin: index() stores the points cell by cell,
    /// so cell c holds points point_start[c] .. point_start[c + 1] - 1.
    std::vector<std::uint32_t> point_start;
    /// An edge as a tick reads it: its ends, and the ball around it (middle and half its length),
    /// which rejects most edges near the tool without reading their ends' positions.
    struct Edge {
        Eigen::Vector2i ends;
        Eigen::Vector3f middle;
        float half_length;
    };
    std::vector<std::uint32_t> edge_start; ///< per cell (and one more) into `edges`
    std::vector<Edge> edges;               ///< cell by cell
    /// The slack (SurfacePoints::slack_pose) of each point and of each entry of `edges`, mm, so
    /// that a tick reads the slack of what it leaves out and nothing more; empty: no slack.
    std::vector<float> point_slack, edge_slack;
    double longest_edge_mm = 0.0;
};

/// The subdivided patch of surface at a tool's contact (contact/contact_patch.hpp), built with the
/// snapshot in the simulation thread; the haptic thread displaces its points (ContactPatchState).
/// Its points are the Loop-subdivided triangles around the contact: the first `free` move along
/// their inward normal against home springs (to where the snapshot has them) and mesh springs
/// (along the fine edges); the rest, its border on the snapshot's surface, stay. Laid out as the
/// 1 kHz tick reads it: what concerns the free points alone, in their order, so that a tick takes
/// a new patch without copying or filtering it.
struct PatchLayer {
    std::size_t count = 0;                    ///< points (0: no patch)
    std::size_t free = 0;                     ///< the first `free` move
    int level = 0;                            ///< Loop subdivisions of the snapshot's triangles
    std::vector<Eigen::Vector3d> positions_mm, normals;
    std::vector<double> areas_mm2;
    std::vector<Eigen::Vector3i> triangles;
    /// The fine edges between two free points, each once (smaller index first, in order): the
    /// edges the tool's contact presses (one with a held end is the snapshot's border, and stays).
    std::vector<Eigen::Vector2i> free_edges;
    double longest_free_edge_mm = 0.0;        ///< where the patch was built
    /// Per free point, its free neighbours, `neighbour_slots` of them (one with fewer is padded
    /// with `free`, the index of a zero the product reads): free_neighbours[i * neighbour_slots ..].
    /// The same count for every point, so that the tick's loop over them is always predicted. A
    /// mesh spring to a held point (u = 0) adds only to the diagonal.
    std::size_t neighbour_slots = 0;
    std::vector<std::uint32_t> free_neighbours;
    /// Per free point, the springs' diagonal: its home spring plus a mesh spring per neighbour.
    std::vector<double> spring_diagonal_n_per_mm;
    double mesh_n_per_mm = 0.0;               ///< per edge
    /// Per free point, the load (N, inward) the tool pressed it with where the patch was built:
    /// the snapshot holds the deformation under it, so the springs carry only what changes.
    std::vector<double> preload_n;
    /// Per free point that is a snapshot point carried to the fine level: that point, else -1
    /// (what the patch hands back: its displacement at the snapshot's points).
    std::vector<std::int32_t> snapshot_point;
    /// The FEM's compliance the springs were scaled to: load-weighted displacement per newton.
    double compliance_mm_per_n = 0.0;
    /// Per free point, how far the springs give under the preload alone, mm: the shape the
    /// haptic side starts a new patch displaced along, so the force carries on from the last
    /// patch's instead of jumping to the new snapshot's (ContactPatchState::step).
    std::vector<double> preload_give_mm;

    /// The springs' force on free point i at displacements x (per free point along the inward
    /// normal, and x[free] = 0): K x at i. Both sides use it, the build's solve and the tick's
    /// (with the contact's stiffness added to the diagonal there: `diagonal`).
    template <class X> [[nodiscard]] double spring_product(std::size_t i, const X& x, double diagonal) const noexcept
    {
        const std::uint32_t* neighbour = free_neighbours.data() + i * neighbour_slots;
        double pull = 0.0;
        for (std::size_t k = 0; k < neighbour_slots; ++k) pull += x[neighbour[k]];
        return diagonal * x[i] - mesh_n_per_mm * pull;
    }
};

struct SurfacePoints {
    double t_s = -1e300;                      ///< simulated time the positions are from
    std::size_t count = 0;                    ///< points in use (the vectors hold capacity())
    std::vector<Eigen::Vector3d> positions_mm;
    std::vector<Eigen::Vector3d> normals;     ///< outward, unit
    std::vector<double> areas_mm2;
    /// Per point, the contact's stiffness as ContactParameters::stiffness_n_per_mm (N/mm per cm^2
    /// of contact), where the material sets it (shape matching's constraint particles,
    /// docs/shape-matching.md); empty: the tool's own.
    std::vector<double> stiffness_n_per_mm;
    bool truncated = false;                   ///< more points were near than the capacity holds
    /// Surface triangles whose three corners are among the points (indices into them), and a box
    /// tree over them (a static mesh: start = end) for the continuous tool-mesh check.
    std::vector<Eigen::Vector3i> triangles;
    SweptBvh triangle_tree;
    /// The triangles' edges, each once (surface_edges): what the edge penalty presses.
    std::vector<Eigen::Vector2i> edges;

    /// The points' grid (index()).
    PointGrid grid;

    /// The subdivided patch at the contact, if any (contact/contact_patch.hpp), and per point
    /// whether the patch stands in for it (empty: none): the contact leaves those points, and the
    /// edges with such an end, to the patch.
    PatchLayer patch;
    std::vector<unsigned char> replaced;
    [[nodiscard]] bool is_replaced(std::size_t i) const noexcept { return i < replaced.size() && replaced[i] != 0; }

    /// What a tick of the 1 kHz loop may leave out (measure_slack, contact/penalty_contact.hpp,
    /// after index()): the tool's pose and margin the snapshot was measured against; per point
    /// and per edge (grid.point_slack, grid.edge_slack), how far the tool may move from that pose
    /// before the point or edge can take part in the contact, 0 where it does, or may. A tick
    /// moves the tool micrometres, and a snapshot is new every few ticks, so most of a knife's
    /// crack walls, a hair outside its margin, need not be measured again until the next one.
    PlacedShape slack_pose;                   ///< no shape: no slack (nothing is left out)
    double slack_margin_mm = 0.0;
    double slack_radius_mm = 0.0;             ///< farthest point from slack_pose.position

    explicit SurfacePoints(std::size_t capacity = 0)
        : positions_mm(capacity), normals(capacity), areas_mm2(capacity)
    {
    }
    [[nodiscard]] std::size_t capacity() const { return positions_mm.size(); }

    /// After the points and triangles are filled (simulation thread): the points' grid, the
    /// points reordered cell by cell (the triangles follow them), the triangles' tree and their
    /// edges.
    void index();

    /// How far the points may have come nearer to `tool` (pushing margin `margin_mm`) than they
    /// were to the tool at slack_pose: its move plus its turn times the farthest point's distance
    /// (a distance is 1-Lipschitz); infinity when the slack is for another shape or margin.
    [[nodiscard]] double slack_spent(const PlacedShape& tool, double margin_mm) const noexcept
    {
        if (!slack_pose.shape || slack_pose.shape != tool.shape || slack_margin_mm != margin_mm) return INFINITY;
        return (tool.position - slack_pose.position).norm() + tool.orientation.angularDistance(slack_pose.orientation) * slack_radius_mm;
    }

    /// Calls visit(i) for every point that may lie in `box` (at least those that do), leaving out
    /// those whose slack exceeds `spent` (none with the default); never allocates.
    template <class Visit> void for_each_point_near(const Eigen::AlignedBox3d& box, Visit&& visit, double spent = INFINITY) const noexcept
    {
        if (grid.cell_mm <= 0.0) {
            for (std::size_t i = 0; i < count; ++i) visit(i);
            return;
        }
        const bool slack = spent < INFINITY && grid.point_slack.size() == count;
        for_each_cell(box, [&](std::size_t c) {
            for (std::uint32_t k = grid.point_start[c]; k < grid.point_start[c + 1]; ++k)
                if (!slack || grid.point_slack[k] <= spent) visit(static_cast<std::size_t>(k));
        });
    }
    /// Calls visit(edge) (its two ends) for every edge that may meet `box` (at least those that
    /// do), leaving out those whose slack exceeds `spent` (none with the default).
    template <class Visit> void for_each_edge_near(const Eigen::AlignedBox3d& box, Visit&& visit, double spent = INFINITY) const noexcept
    {
        if (grid.cell_mm <= 0.0) {
            for (const Eigen::Vector2i& e : edges) visit(e);
            return;
        }
        const bool slack = spent < INFINITY && grid.edge_slack.size() == grid.edges.size();
        // An edge meets the box only if its middle lies within half its length of the box.
        const Eigen::Vector3d grow = Eigen::Vector3d::Constant(0.5 * grid.longest_edge_mm);
        const Eigen::Vector3f lo = box.min().cast<float>(), hi = box.max().cast<float>();
        for_each_cell(Eigen::AlignedBox3d(box.min() - grow, box.max() + grow), [&](std::size_t c) {
            for (std::uint32_t k = grid.edge_start[c]; k < grid.edge_start[c + 1]; ++k) {
                if (slack && grid.edge_slack[k] > spent) continue;
                const PointGrid::Edge& e = grid.edges[k];
                // A float's rounding is far below the 1e-3 mm slack.
                const float h = e.half_length + 1e-3f;
                if ((e.middle.array() + h < lo.array()).any() || (e.middle.array() - h > hi.array()).any()) continue;
                visit(e.ends);
            }
        });
    }

private:
    template <class Visit> void for_each_cell(const Eigen::AlignedBox3d& box, Visit&& visit) const noexcept
    {
        Eigen::Vector3i lo, hi;
        for (int a = 0; a < 3; ++a) {
            lo[a] = std::max(0, static_cast<int>(std::floor((box.min()[a] - grid.origin[a]) / grid.cell_mm)));
            hi[a] = std::min(grid.cells[a] - 1, static_cast<int>(std::floor((box.max()[a] - grid.origin[a]) / grid.cell_mm)));
            if (!(box.max()[a] >= grid.origin[a]) || lo[a] > hi[a]) return; // outside the grid (or a NaN box)
        }
        for (int z = lo.z(); z <= hi.z(); ++z)
            for (int y = lo.y(); y <= hi.y(); ++y)
                for (int x = lo.x(); x <= hi.x(); ++x)
                    visit(static_cast<std::size_t>(x + grid.cells.x() * (y + static_cast<std::size_t>(grid.cells.y()) * z)));
    }
};

} // namespace vox::contact
