#pragma once
// The NRRD reader's full result, for readers built on NRRD (3D Slicer's .seg.nrrd): the volume
// as one or several layers, and the header's free-form "key:=value" pairs.

#include "io/volume.hpp"

#include <map>
#include <string>
#include <vector>

namespace vox::io {

struct NrrdImage {
    std::vector<Volume> layers;               ///< one, or one per sample of a leading list axis
    std::map<std::string, std::string> pairs; ///< "key:=value" lines, key as written
};

/// Reads a NRRD file as read_nrrd does; with `layered`, a non-spatial first axis of several
/// samples (Slicer's layers of overlapping segments) is read as that many volumes instead of
/// being refused.
[[nodiscard]] NrrdImage read_nrrd_image(const std::string& path, bool layered);

/// The header's "key:=value" pairs alone (the data is not read).
[[nodiscard]] std::map<std::string, std::string> read_nrrd_pairs(const std::string& path);

} // namespace vox::io
