#pragma once
// Is-XFEM's finite-element mesh as ParaView reads it (io/vtu_writer.hpp): its uncut tetrahedra on
// shared nodes, and each cut tetrahedron as the sub-tetrahedra of its sides, every side placed by
// its own enriched field, so that the cracks open in the picture as they do in the model.

#include "io/vtu_writer.hpp"

namespace vox::grid {
class LabelGrid;
}

namespace vox::sim {

class IsxfemSimulation;

/// The same cell fields as the branched grid's (dbg_fem_mesh.hpp), plus `region` (a cut
/// tetrahedron's side pattern, -1 uncut): `level`; `piece` (cells joined through shared nodes or
/// sides); `dominant_label` and `fraction_label_L`, the label of the voxel at the cell's rest
/// centroid; `plastic_strain` and `water` 0 (the method models neither); `von_mises_pa` from the
/// corotational strain of the side's linear field.
[[nodiscard]] io::VtuMesh isxfem_fem_mesh(const IsxfemSimulation& sim, const grid::LabelGrid& labels, int level);

} // namespace vox::sim
