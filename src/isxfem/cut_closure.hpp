#pragma once
// Closing a surface embedded in an Is-XFEM model along its cuts, so that what is rendered, touched
// and exported is a closed surface whatever the cut: a cut through the object, or a slit that stops
// inside it.
//
// Per cut, along its surface (a plane, or a blade's swept surface: isxfem/cut_surface.hpp): the
// crack is R, the union of the cut's polygons in the tetrahedra it separated; the object's
// cross-section is S, bounded by where the cut's level crosses the surface's triangles. A triangle whose crossing lies in R is split along it, each piece on its side (the
// crossing points get one copy per side); where a crossing leaves R inside a triangle, the crack
// ends there (a front point, one vertex shared by both sides) and the rest of the triangle stays
// whole. The crack's faces are S and R intersected: S's boundary inside R (the split crossings)
// joined by R's boundary inside S (the crack front, shared by both sides, where the two faces
// meet), both walked with their region on the left, as in Weiler and Atherton's polygon clipping.
// Each face is triangulated twice, once per side, facing out of its side.

#include "isxfem/xfem_model.hpp"

#include <Eigen/Core>

#include <array>
#include <cstdint>
#include <vector>

namespace vox::isxfem {

/// A material point of an embedded surface: a tetrahedron, barycentric coordinates there and the
/// region of the tetrahedron it lies in (XfemElement::region_at: its side of each cut, 0 when
/// uncut), with its rest position.
struct SurfacePoint {
    std::size_t tet = 0;
    std::array<double, 4> bary{};
    int side = 0; ///< the region
    Eigen::Vector3d rest_m = Eigen::Vector3d::Zero();
    std::int32_t label = 0;
};

struct ClosureCounts {
    std::size_t faces = 0;       ///< crack faces filled (each on both sides)
    std::size_t slit_faces = 0;  ///< of them, closed along a crack front inside the object
    std::size_t open_chains = 0; ///< crossings that could not be closed (left open, counted)
    ClosureCounts& operator+=(const ClosureCounts& o)
    {
        faces += o.faces;
        slit_faces += o.slit_faces;
        open_chains += o.open_chains;
        return *this;
    }
};

class CutClosure {
public:
    explicit CutClosure(const XfemModel& model);

    /// Splits `triangles` (indices into `points`) along cut `cut` and fills its crack on both
    /// sides; new points are appended. With `crack_of` (per triangle: the cut whose crack face it
    /// is, -1 for the object's own surface; missing entries taken as -1), it is kept in step: the
    /// pieces of a split triangle keep its entry, the new faces get `cut`.
    ClosureCounts close(int cut, std::vector<SurfacePoint>& points, std::vector<Eigen::Vector3i>& triangles,
                        std::vector<std::int32_t>* crack_of = nullptr) const;

private:
    const XfemModel& m_model;
    std::vector<std::array<std::int32_t, 4>> m_neighbours;
};

} // namespace vox::isxfem
