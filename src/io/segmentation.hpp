#pragma once
// 3D Slicer's segmentations (.seg.nrrd): a NRRD label map, one layer or several (a leading list
// axis, for segments that overlap), whose header names each segment in "Segment<N>_<key>:=value"
// pairs (Slicer's format description, "Segmentation labelmap representation"): ID, Name, Color
// (r g b in 0..1), LabelValue (default 1), Layer (default N: older files kept one segment a
// layer), Extent, Tags. Read by segment, and written back on the scan's own grid.

#include "grid/label_grid.hpp"

#include <Eigen/Core>

#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

namespace vox::io {

struct Segment {
    std::string id;
    std::string name;
    Eigen::Vector3d color{0.5, 0.5, 0.5}; ///< RGB, 0..1
    std::int32_t label_value = 1;         ///< its voxels' value in its layer
    int layer = 0;
    std::string tags; ///< as written ("key:value|key:value|")
};

/// True for a name ending in .seg.nrrd (any case).
[[nodiscard]] bool is_segmentation_path(const std::string& path);

/// The segments a .seg.nrrd header names, in file order (its data is not read). Throws InputError
/// naming the file when it names none or a value is malformed.
[[nodiscard]] std::vector<Segment> read_segments(const std::string& path);

/// The segments picked by `names` (each a segment's name or ID), in that order; all of them when
/// `names` is empty. Throws InputError naming the file and listing its segments when a name is not
/// there, or names two segments.
[[nodiscard]] std::vector<Segment> pick_segments(const std::vector<Segment>& all, const std::vector<std::string>& names,
                                                 const std::string& path);

/// The voxels of the segments picked (see pick_segments), segment k of the pick getting label
/// k + 1; where picked segments overlap the later in the pick wins. The grid's metadata holds the
/// pick (segment_metadata) and the scan's size ("scan_dims"), so that what is written back keeps
/// names, colours and the grid.
[[nodiscard]] grid::LabelGrid read_segmentation(const std::string& path, const std::vector<std::string>& names);

/// The segments as label grid metadata: a JSON array of {"label", "id", "name", "color", "tags"}.
[[nodiscard]] std::string segment_metadata(const std::vector<Segment>& picked);
/// Label -> segment from a grid's "segments" metadata (empty when it has none).
[[nodiscard]] std::vector<std::pair<std::int32_t, Segment>> segments_of(const grid::LabelGrid& labels);

} // namespace vox::io
