#pragma once
// Which fine voxels a cut takes (Jerabkova et al. 2010, section 3), and which faces a separating
// cut opens.
//  - remove: from the voxels of the surface vertices in contact with the tool, a flood through
//    face neighbours whose deformed centres lie inside the cutting (inner) shape: what is inside
//    the blade now goes;
//  - separate (ours, beyond the paper, which names its volume loss as a limitation): every voxel
//    stays; the cutting surface swept over the stroke opens the face between two neighbours when
//    the segment joining their rest centres crosses it (a centre exactly on the surface counts as
//    lying on the side its normal points to), so a thin blade splits the object, never cuts out
//    a slab. The stroke is followed in rest space: each section the tool cuts with is carried
//    back by the mean displacement of the material around it, and the next sweep starts where the
//    last one ended there, so strokes join without gaps or double cuts (which would leave joined
//    bridges or free slivers) however the material moves meanwhile.

#include "contact/tool_shape.hpp"
#include "cut/model_surface.hpp"

#include <array>
#include <utility>
#include <vector>

namespace vox::cut {

/// Voxel slots to remove: flood from the voxels of `seed_vertices` (surface vertex slots in
/// contact with the tool) through face-connected voxels whose deformed centres are inside `inner`
/// (closer than `reach_mm` to it, when given: a drill's teeth reach past its body).
[[nodiscard]] std::vector<std::uint32_t> voxels_inside(const ModelSurface& surface, const std::vector<Eigen::Vector3d>& node_positions,
                                                       const contact::PlacedShape& inner, const std::vector<std::uint32_t>& seed_vertices,
                                                       double reach_mm = 0.0);

/// The surface a tool cuts along, swept over one stroke, as triangles: its section at both ends
/// of the stroke and the band each edge of the section sweeps between them.
struct SweptSurface {
    std::vector<std::array<Eigen::Vector3d, 3>> triangles;
    /// The tool's y axis at the end of the stroke: which side a centre lying on the surface counts on.
    Eigen::Vector3d normal = Eigen::Vector3d::UnitY();
    [[nodiscard]] Eigen::AlignedBox3d bounds() const;
};

/// A tool's cutting section at `pose`, world mm, as a convex polygon: blade and scalpel: the
/// profile at mid-thickness (y = 0); sphere: the disc through its centre normal to its y axis;
/// mesh: the rectangle of its bounds at y = 0; grown in its plane by `margin` (the pushing
/// shape's margin: the material the edge presses on, at a pressure above the threshold, is the
/// material that gives way).
[[nodiscard]] std::vector<Eigen::Vector3d> section_polygon(const contact::ToolShape& shape, double margin,
                                                           const contact::PlacedShape& pose);
/// The surface polygon `from` sweeps moving to `to` (same vertex count, in order).
[[nodiscard]] SweptSurface sweep_polygons(const std::vector<Eigen::Vector3d>& from, const std::vector<Eigen::Vector3d>& to,
                                          const Eigen::Vector3d& normal);
/// The section of `shape` swept from pose `from` to pose `to`.
[[nodiscard]] SweptSurface sweep_section(const contact::ToolShape& shape, double margin, const contact::PlacedShape& from,
                                         const contact::PlacedShape& to);

/// Whether the segment p-q crosses the triangle, with the side rule above (`normal` orients the
/// triangle's plane).
[[nodiscard]] bool segment_crosses(const Eigen::Vector3d& p, const Eigen::Vector3d& q, const std::array<Eigen::Vector3d, 3>& triangle,
                                   const Eigen::Vector3d& normal);

/// Mean displacement (mm) of the nodes of the elements whose deformed corner box meets `box`
/// (world mm): how far the material around a tool has moved from rest.
[[nodiscard]] Eigen::Vector3d mean_displacement_mm(const ModelSurface& surface, const std::vector<Eigen::Vector3d>& node_positions,
                                                   const Eigen::AlignedBox3d& box);

/// Connected faces whose rest-centre segment crosses `rest_swept` (a swept surface in rest
/// space, world mm): each as (voxel coordinate, axis) of the face between the voxel and its
/// +axis neighbour, in the form BranchedGrid::update takes.
[[nodiscard]] std::vector<std::pair<grid::Coord, int>> faces_crossed(const grid::FineVoxels& voxels, const SweptSurface& rest_swept);

} // namespace vox::cut
