#pragma once
// Which fine voxels a cut takes (Jerabkova et al. 2010, section 3), and which faces a separating
// cut opens.
//  - remove: from the voxels of the surface vertices in contact with the tool, a flood
//    through face neighbours whose deformed centres lie inside that shape;
//  - separate (ours, beyond the paper, which names its volume loss as a limitation): every voxel
//    stays; the cutting surface swept over the stroke opens the face between two neighbours when
//    the segment joining their centres crosses it (a centre exactly on the surface counts as lying
//    on the side its normal points to), so a thin blade splits the object, never cuts out a slab.
//    The centres are the deformed ones: each voxel is on one side whatever pair it is tested in
//    (testing each pair by its rest segment moved to where the pair is cuts neighbouring rows at
//    different faces, and the pieces stay joined through the faces between those rows), and the
//    cut meets the material where the user sees it. On an object at rest they are the rest
//    centres, and the side rule is exact.
// Removal tests deformed centres: what is inside the blade now goes.

#include "contact/tool_shape.hpp"
#include "cut/model_surface.hpp"

#include <array>
#include <utility>
#include <vector>

namespace vox::cut {

/// Voxel slots to remove: flood from the voxels of `seed_vertices` (surface vertex slots in
/// contact with the tool) through face-connected voxels whose deformed centres are inside `inner`.
[[nodiscard]] std::vector<std::uint32_t> voxels_inside(const ModelSurface& surface, const std::vector<Eigen::Vector3d>& node_positions,
                                                       const contact::PlacedShape& inner, const std::vector<std::uint32_t>& seed_vertices);

/// The surface a tool cuts along, swept over one stroke from `from` to `to`, world mm: its
/// cutting section (blade and scalpel: the profile at mid-thickness, y = 0; sphere: the disc
/// through its centre normal to its y axis; mesh: the rectangle of its bounds at y = 0), grown in
/// its plane by `margin` (the pushing shape's margin: the material the edge presses on, at a
/// pressure above the threshold, is the material that gives way), at both poses, and the band
/// each edge of the section sweeps between them.
struct SweptSurface {
    std::vector<std::array<Eigen::Vector3d, 3>> triangles;
    /// The tool's y axis at the end of the stroke: which side a centre lying on the surface counts on.
    Eigen::Vector3d normal = Eigen::Vector3d::UnitY();
    [[nodiscard]] Eigen::AlignedBox3d bounds() const;
};
[[nodiscard]] SweptSurface sweep_section(const contact::ToolShape& shape, double margin, const contact::PlacedShape& from,
                                         const contact::PlacedShape& to);

/// Whether the segment p-q crosses the triangle, with the side rule above (`normal` orients the
/// triangle's plane; an end within 1e-9 of |q - p| of the plane counts as on it, so rounding cannot
/// put one centre on different sides of the coplanar triangles of a section).
[[nodiscard]] bool segment_crosses(const Eigen::Vector3d& p, const Eigen::Vector3d& q, const std::array<Eigen::Vector3d, 3>& triangle,
                                   const Eigen::Vector3d& normal);

/// Connected faces crossed by `swept`: each as (voxel coordinate, axis) of the face between the
/// voxel and its +axis neighbour, in the form BranchedGrid::update takes.
[[nodiscard]] std::vector<std::pair<grid::Coord, int>> faces_crossed(const ModelSurface& surface,
                                                                     const std::vector<Eigen::Vector3d>& node_positions,
                                                                     const SweptSurface& swept);

} // namespace vox::cut
