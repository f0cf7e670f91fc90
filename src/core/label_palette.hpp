#pragma once
// The one palette of label colours: every picture, `.glb`, `.seg.nrrd` and the viewer colour a label
// that has no colour of its own (a segmentation's) from it, so a label map looks the same here as
// in 3D Slicer. It is Slicer's generic anatomy table (data/palette/GenericAnatomyColors.txt,
// labels 0-309: 1 tissue, 2 bone, 13 grey matter, 14 white matter ...), read into the program when
// it is built. A label outside the table takes one of its colours, the same every time.

#include <Eigen/Core>

#include <cstdint>

namespace vox {

/// RGB in 0..1.
[[nodiscard]] Eigen::Vector3d label_color(std::int32_t label);

} // namespace vox
