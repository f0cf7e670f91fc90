#pragma once
// What a cut goes along: a level function phi, negative on one side, positive on the other and
// zero on the cut, and where the cut reaches. Either a plane (PlaneCut; the caller says where in
// it the cut reaches), or a blade's swept surface: flat convex patches, one per frame of a stroke,
// each what the blade's mid-plane swept over that frame (sim/blade_stroke.hpp). A stroke that turns
// or tilts as it goes leaves patches that turn with it, so its cut follows the blade's path
// rather than one plane.
//
// A tetrahedron edge is cut where it meets a patch: Möller and Trumbore's segment-triangle test
// on the patches' triangles (the sculpting paper finds its cut tetrahedra with Möller's
// triangle-triangle test; an edge's crossings are what the cut needs). The level of
// a point is its signed distance from the plane of the patch nearest to it: exact for a stroke
// in one plane, and along a curved one the local tangent plane (XfemModel keeps the levels of the
// nodes it cut with, so the cut is planar in each tetrahedron and continuous between them).

#include "isxfem/plane_cut_system.hpp"

#include <Eigen/Core>
#include <Eigen/Geometry>

#include <vector>

namespace vox::isxfem {

/// A flat convex piece of a swept surface, world m.
struct CutPatch {
    std::vector<Eigen::Vector3d> corners;              ///< convex, in one plane (CutSurface::add turns them counter-clockwise seen from +normal)
    Eigen::Vector3d normal = Eigen::Vector3d::UnitX(); ///< unit; the positive side
    // Set by CutSurface::add: the patch's place in the surface unrolled flat.
    Eigen::Vector3d u = Eigen::Vector3d::UnitY(); ///< an axis in its plane (u, normal x u, normal right-handed)
    Eigen::Vector2d at = Eigen::Vector2d::Zero(); ///< corners[0] unrolled
};

class CutSurface {
public:
    /// A swept surface, patches to come (add()).
    CutSurface() = default;
    /// All of a plane.
    explicit CutSurface(const PlaneCut& plane);

    /// Appends a swept surface's patch, the next along the sweep (a patch with fewer than three
    /// corners covers nothing).
    void add(CutPatch patch);
    [[nodiscard]] bool is_plane() const { return m_is_plane; }
    [[nodiscard]] const std::vector<CutPatch>& patches() const { return m_patches; }

    /// phi at x: the plane's, or the signed distance from the plane of the nearest patch (a
    /// surface without patches: 0).
    [[nodiscard]] double level(const Eigen::Vector3d& x) const;
    /// The unit normal at x: the plane's, or the nearest patch's (the x axis without patches).
    [[nodiscard]] Eigen::Vector3d normal(const Eigen::Vector3d& x) const;
    /// Coordinates of x (on or near the surface) in the surface unrolled flat, counter-clockwise
    /// seen from its positive side: a plane's own, or the nearest patch's, each patch's axis carried
    /// over from the one before by the turn between their normals, so a stroke that turns and
    /// comes round lies flat without folding over itself (what its crack faces are triangulated in).
    [[nodiscard]] Eigen::Vector2d unrolled(const Eigen::Vector3d& x) const;
    /// Whether the segment a-b meets a patch (a plane: whether it crosses it).
    [[nodiscard]] bool meets(const Eigen::Vector3d& a, const Eigen::Vector3d& b) const;
    /// Whether x lies within `off` of a patch's plane and over the patch (a plane: always): where a
    /// tetrahedron edge's level crosses, next to a patch, when the edge's ends lie so close to the
    /// surface that the patches themselves pass beside it.
    [[nodiscard]] bool covers(const Eigen::Vector3d& x, double off) const;
    /// The box of patches [first, end) (a plane: unbounded).
    [[nodiscard]] Eigen::AlignedBox3d bounds(std::size_t first = 0) const;

private:
    /// The patch nearest to x.
    [[nodiscard]] std::size_t nearest(const Eigen::Vector3d& x) const;

    bool m_is_plane = false;
    PlaneCut m_plane;
    std::vector<CutPatch> m_patches;
    std::vector<Eigen::AlignedBox3d> m_boxes; ///< per patch
};

} // namespace vox::isxfem
