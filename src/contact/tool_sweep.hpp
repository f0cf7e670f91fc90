#pragma once
// Continuous collision of the tool with the surface snapshot over one haptic tick, for the proxy:
// first the surface points against the pushing shape's exact distance (swept_contact.hpp), then
// the tool's own triangle mesh (the inner shape: a box mesh grown by the margin would stick out of
// the rounded pushing shape at its corners) against the snapshot's triangles with the exact vertex-face
// and edge-edge tests (ccd.hpp: the cubic coplanarity condition under interval bounds, behind
// Tang et al. 2010's non-penetration filter), pairs found through the snapshot's box tree. The
// mesh test catches what points cannot: a feature of the tool thinner than the spacing of the
// surface's vertices passing through a face or across an edge between them.
//
// It runs on ticks whose move is longer than the margin (a jump, which is how a thin tool passes
// a thin wall); slower moves let the tool's edge into a face between points, as the point contact
// always has (cutting needs the blade to reach the points it cuts), and a tool that already
// straddles a face at the start of a tick is in it, not crossing it. Only surface triangles none
// of whose corners is in the contact at the start of the tick take part (the penalty contact
// holds the rest), and only those the move can reach: a jab that would end with the tool deep in
// the object, its far face against the surface, stops where it first meets it. A contact
// found there stops the tool 1 um before it: it is held at the face like a god-object, and the
// user feels the coupling spring. Everything here runs in the 1 kHz loop: the buffers are sized
// at construction; no allocation, lock, log or throw.

#include "contact/surface_points.hpp"
#include "contact/tool_shape.hpp"

#include <array>
#include <vector>

namespace vox::contact {

class ToolSweep {
public:
    /// `point_capacity`: the largest snapshot the loop will see (its capacity()); a larger one
    /// gets the point test only.
    ToolSweep(const ToolShape& shape, double margin_mm, std::size_t point_capacity);

    /// The earliest time t in [0, 1] of the move from `from` to `to` (same shape as given at
    /// construction) that the tool must stop at; 1 when it can go all the way. Tool vertices are
    /// taken to move linearly over the tick (a tick turns the tool by a small fraction of a degree).
    /// `from_distance`: the points' signed distances at `from` already measured this tick
    /// (penalty_totals), +infinity where not.
    [[nodiscard]] double first_stop(const PlacedShape& from, const PlacedShape& to, const SurfacePoints& points,
                                    std::span<const double> from_distance = {}) noexcept;

    /// Whether the last first_stop() ran the mesh test (a move longer than the margin), and
    /// whether the mesh test decided it (a feature between points).
    [[nodiscard]] bool swept_mesh() const { return m_swept_mesh; }
    [[nodiscard]] bool stopped_by_mesh() const { return m_stopped_by_mesh; }

private:
    /// Whether surface triangle `triangle` (no corner in the contact) is near enough for a move
    /// of `speed` mm to reach it. Measures corners the point test left unmeasured.
    bool reachable(const Eigen::Vector3i& triangle, const PlacedShape& from, const SurfacePoints& points, double speed) noexcept;

    double m_margin;
    TriangleMesh m_local;                       ///< the inner shape, tool frame
    std::vector<std::array<int, 2>> m_edges;    ///< its edges, each once
    std::vector<Eigen::Vector3d> m_start, m_end; ///< its vertices in the world at both ends
    std::vector<double> m_clearance;            ///< per snapshot point (see first_missed_contact)
    bool m_swept_mesh = false, m_stopped_by_mesh = false;
};

} // namespace vox::contact
