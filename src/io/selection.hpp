#pragma once
// Which voxels of a scan become the object: by label, by a value window, or every non-zero voxel.

#include "grid/label_grid.hpp"
#include "io/piece_selection.hpp"
#include "io/volume.hpp"

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

namespace vox::io {

/// At most one of `labels` and `threshold_min` is set. With labels, voxels whose stored value is
/// one of them keep that label. With a threshold, voxels whose scaled value (slope * stored +
/// intercept, e.g. Hounsfield units) lies in [threshold_min, threshold_max] (inclusive; no upper
/// bound when max is unset) get label 1. With neither, every non-zero voxel keeps its value as label.
/// Then `pieces` chooses among the pieces (6-connected components) of the voxels selected.
/// One band of `threshold_bands`: voxels whose scaled value lies in [min, max] get `label`.
struct ThresholdBand {
    double min = 0.0;
    double max = 0.0;
    std::int32_t label = 1;
};

struct Selection {
    std::vector<std::int32_t> labels;
    std::optional<double> threshold_min;
    std::optional<double> threshold_max;
    /// Several tissues from one scan (a CT's bone and soft tissue): each band its own label; where
    /// bands overlap the first listed wins. Exclusive with labels and the threshold.
    std::vector<ThresholdBand> bands;
    /// 3D Slicer segmentations (.seg.nrrd) only, instead of the three above: the segments kept,
    /// by name or ID, labelled 1, 2, ... in this order (empty: every segment). io/segmentation.hpp.
    std::vector<std::string> segments;
    PieceSelection pieces;

    /// No label, threshold or band: every non-zero voxel, keeping its value (pieces aside).
    [[nodiscard]] bool empty() const { return labels.empty() && !threshold_min && bands.empty(); }
    /// "label 255", "threshold [226, 3071]", "every non-zero voxel": for messages.
    [[nodiscard]] std::string describe() const;
};

/// Parses "LO" or "LO:HI" (inclusive). Throws InputError on malformed text or LO > HI.
[[nodiscard]] Selection parse_threshold(const std::string& text);

/// The selected voxels of a scan, in an int grid with the scan's index-to-world transform.
/// Throws InputError naming the scan when nothing is selected (listing the values present) or
/// when, without a selection, a non-zero value is not an integer label.
[[nodiscard]] grid::LabelGrid select_voxels(const Volume& volume, const Selection& selection);

/// The same selection applied to an existing label grid (a .vdb file); `source` names it.
[[nodiscard]] grid::LabelGrid select_labels(const grid::LabelGrid& labels, const Selection& selection,
                                            const std::string& source);

} // namespace vox::io
