#pragma once
// DICOM series in: a folder of a CT or MR export (one image per file) read through GDCM, in the
// same LPS millimetres as every other volume format. The slices are ordered by their position
// along the normal of their orientation, never by file name or instance number; the stored values
// keep the rescale slope and intercept (Hounsfield units for CT). Patient identifiers are never
// read into anything this returns, so nothing downstream can log or write them.

#include "io/volume.hpp"

#include <array>
#include <cstdint>
#include <string>
#include <vector>

namespace vox::io {

/// One series of a DICOM folder, as `voxsculpt info DIR` lists it.
struct DicomSeries {
    int number = 0;          ///< 1-based place in the listing: what "--series N" picks
    std::string uid;         ///< SeriesInstanceUID
    std::string description; ///< SeriesDescription ("" when absent)
    std::string modality;    ///< CT, MR, ...
    int series_number = -1;  ///< the scanner's SeriesNumber (-1 when absent); orders the listing
    std::array<std::int64_t, 3> size{0, 0, 0}; ///< columns, rows, slices (image files)
    std::vector<std::string> files;            ///< its image files, in no particular order
    std::string problem; ///< why it cannot be read as a volume (the error read_dicom gives), "" when it can
};

/// True for a folder (a DICOM export is a folder of files) and for a file with the DICOM preamble
/// ("DICM" at byte 128) or the .dcm extension.
[[nodiscard]] bool is_dicom_path(const std::string& path);

/// The image series in a folder (searched with its sub-folders) or in one file, ordered by
/// SeriesNumber then UID. Files that are not DICOM images (a DICOMDIR, notes, reports) are
/// skipped. Each series' geometry is checked (`problem`). Throws InputError naming the path when
/// it holds no DICOM image.
[[nodiscard]] std::vector<DicomSeries> list_dicom_series(const std::string& path);

/// Reads one series as a volume. `series`: "" when the path holds exactly one, else the number
/// in the listing ("2") or the SeriesInstanceUID. Refused with a message naming the path: several
/// series and none picked, a series that is not there, colour or multi-frame images, images of
/// different sizes or orientations, two slices at one position, a slice further than 10 % of the
/// spacing from the even grid fitted to the positions (a missing slice; rounded header positions
/// are placed on the grid, with an info line), gantry tilt, pixel data GDCM cannot decode.
[[nodiscard]] Volume read_dicom(const std::string& path, const std::string& series = "");

} // namespace vox::io
