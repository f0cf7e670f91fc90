// DICOM series through GDCM (the one translation unit that includes it).
//
// - Geometry (DICOM PS3.3 C.7.6.2, Image Plane): ImageOrientationPatient holds the row direction
//   r (the direction of increasing column index) and the column direction c, ImagePositionPatient
//   the centre of a slice's first voxel, PixelSpacing the spacing between rows, then between
//   columns. DICOM's patient frame is LPS already. Voxel (i, j, k) is column i, row j of the k-th
//   slice along n = r x c, ordered by n . position: file names and InstanceNumber say nothing
//   reliable about where a slice is.
// - The series must be a regular grid: one orientation, one size, one pixel spacing, slices at
//   even steps along n and stacked straight along n (a gantry-tilted CT is sheared). The steps
//   are those of the even grid fitted to the positions (least squares), which every slice must
//   lie within 10 % of a step from: scanners round the positions they write, while a missing
//   slice leaves one at least half a step off. Anything else is refused with what was found,
//   rather than resampled silently.
// - Values: stored values with one rescale slope and intercept for the series (CT: Hounsfield
//   units), or, when slices carry different ones, rescaled per slice into float.
// - Pixel data: whatever GDCM decodes (native, RLE, JPEG lossless and lossy, JPEG-LS through
//   CharLS, JPEG 2000 through OpenJPEG); a file it cannot decode is named with its transfer syntax.
// - Safety: Debian's GDCM keeps its assertions, and a truncated file aborts the process inside its
//   parser; lengths in a file are trusted. So every listing and read runs first in a child process
//   (core/child_process.hpp) within the memory limit and a time allowed for the bytes, the child
//   noting in a page shared with this process the file it is in, so that a crash names the file;
//   only a clean run is repeated here.
// - Privacy: only the tags below are read (no patient, study date or institution), and messages
//   name files by the path the user gave.

#include "io/dicom_reader.hpp"

#include "core/error.hpp"
#include "core/log.hpp"
#include "core/child_process.hpp"
#include "core/memory_limit.hpp"
#include "io/file_bytes.hpp"

#include <gdcmDirectory.h>
#include <gdcmImage.h>
#include <gdcmImageReader.h>
#include <gdcmScanner.h>
#include <gdcmTrace.h>

#include <Eigen/Geometry>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <map>
#include <numeric>
#include <set>
#include <sstream>

#include <sys/mman.h>

namespace vox::io {
namespace {

const gdcm::Tag k_series_uid(0x0020, 0x000e);
const gdcm::Tag k_series_description(0x0008, 0x103e);
const gdcm::Tag k_modality(0x0008, 0x0060);
const gdcm::Tag k_series_number(0x0020, 0x0011);
const gdcm::Tag k_position(0x0020, 0x0032);
const gdcm::Tag k_orientation(0x0020, 0x0037);
const gdcm::Tag k_rows(0x0028, 0x0010);
const gdcm::Tag k_columns(0x0028, 0x0011);
const gdcm::Tag k_pixel_spacing(0x0028, 0x0030);
const gdcm::Tag k_frames(0x0028, 0x0008);
const gdcm::Tag k_samples(0x0028, 0x0002);
const gdcm::Tag k_slice_thickness(0x0018, 0x0050);

/// GDCM prints its warnings and errors to the console; ours are the messages that count.
void quiet_gdcm()
{
    static const bool done = [] {
        gdcm::Trace::DebugOff();
        gdcm::Trace::WarningOff();
        gdcm::Trace::ErrorOff();
        return true;
    }();
    (void)done;
}

std::string trimmed(const char* text)
{
    if (text == nullptr) return {};
    std::string s(text);
    const auto keep = [](unsigned char ch) { return ch != 0 && !std::isspace(ch); };
    const auto first = std::find_if(s.begin(), s.end(), keep);
    const auto last = std::find_if(s.rbegin(), s.rend(), keep).base();
    return first < last ? std::string(first, last) : std::string();
}

/// A multi-valued decimal string ("a\b\c") of exactly `count` finite numbers, or an empty vector.
std::vector<double> numbers(const std::string& text, std::size_t count)
{
    std::vector<double> out;
    std::string item;
    std::istringstream in(text);
    while (std::getline(in, item, '\\')) {
        const std::string t = trimmed(item.c_str());
        char* end = nullptr;
        const double v = std::strtod(t.c_str(), &end);
        if (t.empty() || end != t.c_str() + t.size() || !std::isfinite(v)) return {};
        out.push_back(v);
    }
    return out.size() == count ? out : std::vector<double>{};
}

/// A whole number in [lo, hi], or -1.
long whole(const std::string& text, long lo, long hi)
{
    char* end = nullptr;
    const long v = std::strtol(text.c_str(), &end, 10);
    return !text.empty() && end == text.c_str() + text.size() && v >= lo && v <= hi ? v : -1;
}

struct Slice {
    std::string file;
    Eigen::Vector3d position;
    double along = 0.0; ///< n . position
};

/// Where a child read is: the file GDCM reads now, in a page shared with the parent.
class Note {
public:
    Note() : m_page(::mmap(nullptr, k_bytes, PROT_READ | PROT_WRITE, MAP_SHARED | MAP_ANONYMOUS, -1, 0))
    {
        if (m_page == MAP_FAILED) throw std::runtime_error("mmap of a shared page failed");
        static_cast<char*>(m_page)[0] = 0;
    }
    ~Note() { ::munmap(m_page, k_bytes); }
    Note(const Note&) = delete;
    Note& operator=(const Note&) = delete;
    /// `header`: GDCM reads the file's header to list it (a file that fails there can be skipped).
    void set(const std::string& file, bool header)
    {
        char* page = static_cast<char*>(m_page);
        const std::size_t n = std::min(file.size(), k_bytes - 2);
        page[0] = header ? 'h' : 'p';
        std::memcpy(page + 1, file.data(), n);
        page[n + 1] = 0;
    }
    [[nodiscard]] std::string file() const { return static_cast<const char*>(m_page) + (m_page_empty() ? 0 : 1); }
    [[nodiscard]] bool header() const { return static_cast<const char*>(m_page)[0] == 'h'; }

private:
    [[nodiscard]] bool m_page_empty() const { return static_cast<const char*>(m_page)[0] == 0; }
    static constexpr std::size_t k_bytes = 4096;
    void* m_page;
};

/// The files under `path` (a folder, searched recursively, or one file) but those in `skip`,
/// scanned for the tags above. With a note (in the child), each file is first scanned alone,
/// noted, so that a crash names it.
struct Scan {
    gdcm::Scanner scanner;
    std::vector<std::string> files;

    Scan(const std::string& path, const std::set<std::string>& skip, Note* note)
    {
        quiet_gdcm();
        std::error_code error;
        if (!std::filesystem::exists(path, error)) throw file_error(path, "no such file or folder");
        if (std::filesystem::is_directory(path, error)) {
            gdcm::Directory d;
            d.Load(path, true);
            for (const std::string& f : d.GetFilenames())
                if (skip.count(f) == 0) files.push_back(f);
            std::sort(files.begin(), files.end());
        } else {
            check_input_file(path); // "is empty" and the rest, as every reader says them
            files = {path};
        }
        if (files.empty()) throw file_error(path, "is an empty folder (expected the files of a DICOM series)");
        add_tags(scanner);
        if (note != nullptr) {
            for (const std::string& f : files) {
                note->set(f, true);
                gdcm::Scanner alone;
                add_tags(alone);
                (void)alone.Scan({f});
            }
            note->set(path, false);
        }
        if (!scanner.Scan(files)) throw file_error(path, "cannot be scanned for DICOM files");
    }
    static void add_tags(gdcm::Scanner& s)
    {
        for (const gdcm::Tag& t : {k_series_uid, k_series_description, k_modality, k_series_number, k_position,
                                   k_orientation, k_rows, k_columns, k_pixel_spacing, k_frames, k_samples,
                                   k_slice_thickness})
            s.AddTag(t);
    }
    [[nodiscard]] std::string value(const std::string& file, const gdcm::Tag& t) const
    {
        return trimmed(scanner.GetValue(file.c_str(), t));
    }
    /// A DICOM image: parsed, with a series and a size.
    [[nodiscard]] bool is_image(const std::string& file) const
    {
        return scanner.IsKey(file.c_str()) && !value(file, k_series_uid).empty() && !value(file, k_rows).empty() &&
               !value(file, k_columns).empty();
    }
};

std::vector<DicomSeries> series_of(const Scan& scan, const std::string& path)
{
    std::map<std::string, DicomSeries> by_uid;
    for (const std::string& f : scan.files) {
        if (!scan.is_image(f)) continue;
        DicomSeries& s = by_uid[scan.value(f, k_series_uid)];
        if (s.files.empty()) {
            s.uid = scan.value(f, k_series_uid);
            s.description = scan.value(f, k_series_description);
            s.modality = scan.value(f, k_modality);
            s.series_number = static_cast<int>(whole(scan.value(f, k_series_number), 0, 1L << 30));
            s.size = {whole(scan.value(f, k_columns), 1, 65535), whole(scan.value(f, k_rows), 1, 65535), 0};
        }
        s.files.push_back(f);
        ++s.size[2];
    }
    if (by_uid.empty())
        throw file_error(path, std::filesystem::is_directory(path) ? "holds no DICOM image (searched with its sub-folders)"
                                                                   : "is not a DICOM image");
    std::vector<DicomSeries> out;
    for (auto& [uid, s] : by_uid) out.push_back(std::move(s));
    std::stable_sort(out.begin(), out.end(), [](const DicomSeries& a, const DicomSeries& b) {
        return a.series_number != b.series_number ? a.series_number < b.series_number : a.uid < b.uid;
    });
    for (std::size_t i = 0; i < out.size(); ++i) out[i].number = static_cast<int>(i + 1);
    return out;
}

std::string listing(const std::vector<DicomSeries>& all)
{
    std::string out;
    for (const DicomSeries& s : all)
        out += (out.empty() ? "" : "; ") + std::to_string(s.number) + ": " + s.modality + " " +
               std::to_string(s.size[0]) + "x" + std::to_string(s.size[1]) + "x" + std::to_string(s.size[2]) +
               (s.description.empty() ? "" : " \"" + s.description + "\"");
    return out;
}

const DicomSeries& pick(const std::vector<DicomSeries>& all, const std::string& series, const std::string& path)
{
    if (series.empty()) {
        if (all.size() == 1) return all.front();
        throw file_error(path, "holds " + std::to_string(all.size()) + " series (" + listing(all) +
                                   "): pick one by number or UID (--series N, or \"series\" in a scene)");
    }
    const long n = whole(series, 1, 1L << 30);
    for (const DicomSeries& s : all)
        if (s.uid == series || s.number == n) return s;
    throw file_error(path, "has no series " + series + " (it holds " + listing(all) + ")");
}

std::string text3(const Eigen::Vector3d& v)
{
    std::ostringstream out;
    out.precision(6);
    out << "(" << v.x() << ", " << v.y() << ", " << v.z() << ")";
    return out.str();
}

ScalarType scalar_type(const gdcm::PixelFormat& pf, const std::string& file)
{
    switch (pf.GetScalarType()) {
    case gdcm::PixelFormat::UINT8: return ScalarType::u8;
    case gdcm::PixelFormat::INT8: return ScalarType::i8;
    case gdcm::PixelFormat::UINT16: return ScalarType::u16;
    case gdcm::PixelFormat::INT16: return ScalarType::i16;
    case gdcm::PixelFormat::UINT32: return ScalarType::u32;
    case gdcm::PixelFormat::INT32: return ScalarType::i32;
    case gdcm::PixelFormat::FLOAT32: return ScalarType::f32;
    case gdcm::PixelFormat::FLOAT64: return ScalarType::f64;
    default:
        throw file_error(file, std::string("pixels of ") + std::to_string(pf.GetBitsAllocated()) +
                                   " bits allocated are not read (expected 8, 16 or 32)");
    }
}

/// How far a slice may lie from the even grid fitted to the series, as a fraction of the slice
/// spacing: header rounding (0.1 mm on 0.5 - 7 mm slices) passes; a missing slice, which leaves
/// some slice at least half a spacing off any even grid, does not.
constexpr double k_slice_tolerance = 0.1;

/// The least-squares even grid through slices sorted along their normal: position k = first +
/// k step (step a vector: its part across the normal is a gantry tilt).
struct SliceGrid {
    Eigen::Vector3d step = Eigen::Vector3d::Zero();
    double first_along = 0.0;  ///< the grid's first slice along the normal
    double worst_offset = 0.0; ///< the furthest slice's distance from the grid along the normal, mm
    std::string worst_file;
};

SliceGrid fit_slice_grid(const std::vector<Slice>& v, const Eigen::Vector3d& n)
{
    const auto count = static_cast<double>(v.size());
    const double mean_k = 0.5 * (count - 1.0);
    Eigen::Vector3d mean_p = Eigen::Vector3d::Zero();
    for (const Slice& slice : v) mean_p += slice.position / count;
    double kk = 0.0;
    Eigen::Vector3d kp = Eigen::Vector3d::Zero();
    for (std::size_t k = 0; k < v.size(); ++k) {
        const double dk = static_cast<double>(k) - mean_k;
        kk += dk * dk;
        kp += dk * (v[k].position - mean_p);
    }
    SliceGrid grid;
    grid.step = kp / kk;
    const double step_along = grid.step.dot(n); // along = n . position: the fit of the positions, seen along n
    grid.first_along = n.dot(mean_p) - step_along * mean_k;
    for (std::size_t k = 0; k < v.size(); ++k)
        if (const double off = std::abs(v[k].along - grid.first_along - step_along * static_cast<double>(k)); off > grid.worst_offset) {
            grid.worst_offset = off;
            grid.worst_file = v[k].file;
        }
    return grid;
}

/// The slices of `s` ordered along their normal, with the volume's geometry checked and built.
struct Stack {
    std::vector<Slice> slices;
    Eigen::Matrix4d index_to_world;
    double moved_mm = 0.0;  ///< how far the furthest slice was moved onto the even grid
    std::string moved_file; ///< that slice's file
};

Stack stack(const Scan& scan, const DicomSeries& s, const std::string& path)
{
    const std::string& first = s.files.front();
    const std::vector<double> orientation = numbers(scan.value(first, k_orientation), 6);
    const std::vector<double> spacing = numbers(scan.value(first, k_pixel_spacing), 2);
    if (orientation.empty()) throw file_error(first, "has no valid ImageOrientationPatient (0020,0037)");
    if (spacing.empty() || spacing[0] <= 0.0 || spacing[1] <= 0.0)
        throw file_error(first, "has no valid PixelSpacing (0028,0030): two positive numbers");
    const Eigen::Vector3d r(orientation[0], orientation[1], orientation[2]);
    const Eigen::Vector3d c(orientation[3], orientation[4], orientation[5]);
    if (std::abs(r.norm() - 1.0) > 1e-3 || std::abs(c.norm() - 1.0) > 1e-3 || std::abs(r.dot(c)) > 1e-3)
        throw file_error(first, "ImageOrientationPatient " + scan.value(first, k_orientation) +
                                    " is not two orthogonal unit vectors");
    const Eigen::Vector3d n = r.normalized().cross(c.normalized());

    Stack out;
    for (const std::string& f : s.files) {
        if (const long frames = whole(scan.value(f, k_frames), 0, 1L << 30); frames > 1)
            throw file_error(f, "is a multi-frame image (" + std::to_string(frames) +
                                    " frames in one file, an enhanced CT or MR export), which is not read: export the "
                                    "series as single-frame images");
        if (const std::string samples = scan.value(f, k_samples); !samples.empty() && samples != "1")
            throw file_error(f, "has " + samples + " samples a pixel (a colour image); a scan series is greyscale");
        if (whole(scan.value(f, k_columns), 1, 65535) != s.size[0] || whole(scan.value(f, k_rows), 1, 65535) != s.size[1])
            throw file_error(path, "series " + std::to_string(s.number) + " mixes image sizes (" + first + " and " + f + ")");
        const std::vector<double> o = numbers(scan.value(f, k_orientation), 6);
        if (o.empty() || std::inner_product(o.begin(), o.end(), orientation.begin(), 0.0,
                                            [](double a, double b) { return std::max(a, b); },
                                            [](double a, double b) { return std::abs(a - b); }) > 1e-4)
            throw file_error(path, "series " + std::to_string(s.number) + " mixes slice orientations (" + first + " and " +
                                       f + "): a localizer or several stacks in one series");
        const std::vector<double> ps = numbers(scan.value(f, k_pixel_spacing), 2);
        if (ps.empty() || std::abs(ps[0] - spacing[0]) > 1e-4 * spacing[0] || std::abs(ps[1] - spacing[1]) > 1e-4 * spacing[1])
            throw file_error(path, "series " + std::to_string(s.number) + " mixes pixel spacings (" + first + " and " + f + ")");
        const std::vector<double> p = numbers(scan.value(f, k_position), 3);
        if (p.empty()) throw file_error(f, "has no valid ImagePositionPatient (0020,0032)");
        Slice slice{f, Eigen::Vector3d(p[0], p[1], p[2]), 0.0};
        slice.along = n.dot(slice.position);
        out.slices.push_back(std::move(slice));
    }
    std::sort(out.slices.begin(), out.slices.end(), [](const Slice& a, const Slice& b) { return a.along < b.along; });

    const std::vector<Slice>& v = out.slices;
    const std::size_t count = v.size();
    double step = 0.0;
    Eigen::Vector3d origin = v.front().position;
    if (count == 1) {
        const std::vector<double> thickness = numbers(scan.value(first, k_slice_thickness), 1);
        step = !thickness.empty() && thickness[0] > 0.0 ? thickness[0] : std::min(spacing[0], spacing[1]);
    } else {
        const double in_plane = std::min(spacing[0], spacing[1]);
        for (std::size_t k = 0; k + 1 < count; ++k)
            if (v[k + 1].along - v[k].along < 1e-3 * in_plane)
                throw file_error(path, "series " + std::to_string(s.number) + " has two slices at " +
                                           text3(v[k].position) + " mm (" + v[k].file + " and " + v[k + 1].file +
                                           "): several phases, echoes or acquisitions in one series are not read");
        // The even grid that fits the positions best (least squares over the slice index), as
        // ITK and 3D Slicer place a series: scanners round the positions they write (to 0.1 mm,
        // even 1 mm), so the gaps between neighbours vary by far more than the grid does.
        const SliceGrid grid = fit_slice_grid(v, n);
        step = grid.step.dot(n);
        const double tolerance = k_slice_tolerance * step;
        if (grid.worst_offset > tolerance) {
            // The gap furthest from the median names the defect (a missing slice shows as a
            // double gap).
            std::vector<double> gaps;
            for (std::size_t k = 0; k + 1 < count; ++k) gaps.push_back(v[k + 1].along - v[k].along);
            std::vector<double> sorted = gaps;
            std::nth_element(sorted.begin(), sorted.begin() + static_cast<std::ptrdiff_t>(sorted.size() / 2), sorted.end());
            const double median = sorted[sorted.size() / 2];
            const auto worst = std::max_element(gaps.begin(), gaps.end(), [&](double a, double b) {
                return std::abs(a - median) < std::abs(b - median);
            });
            const auto k = static_cast<std::size_t>(worst - gaps.begin());
            std::ostringstream msg;
            msg << "series " << s.number << " has uneven slice spacing: " << *worst << " mm between " << v[k].file << " and "
                << v[k + 1].file << " where the slices are " << median << " mm apart elsewhere (a missing slice?: "
                << grid.worst_file << " lies " << grid.worst_offset << " mm off the even grid, more than "
                << 100.0 * k_slice_tolerance << " % of the spacing); resample it to even spacing first";
            throw file_error(path, msg.str());
        }
        // Gantry tilt: the slices are stacked along a direction other than their normal. Read
        // untilted, the last slice would sit this far sideways of where it was scanned.
        const Eigen::Vector3d along = grid.step * static_cast<double>(count - 1);
        const double sideways = (along - along.dot(n) * n).norm();
        const double degrees = std::atan2(sideways, along.dot(n)) * 180.0 / M_PI;
        if (sideways > std::max(tolerance, 0.5 * in_plane) && degrees > 0.01) {
            std::ostringstream msg;
            msg.precision(3);
            msg << "series " << s.number << " is tilted: its slices are stacked " << degrees
                << " degrees off their normal (gantry tilt), which is not read; resample it to an untilted volume first";
            throw file_error(path, msg.str());
        }
        // The first slice moved along the normal onto the grid; the others follow from the step.
        origin += (grid.first_along - v.front().along) * n;
        out.moved_mm = grid.worst_offset;
        out.moved_file = grid.worst_file;
    }
    Eigen::Matrix3d direction;
    direction << r.normalized(), c.normalized(), n;
    out.index_to_world = make_index_to_world(Eigen::Vector3d(spacing[1], spacing[0], step), direction, origin);
    return out;
}

} // namespace

bool is_dicom_path(const std::string& path)
{
    std::error_code error;
    if (std::filesystem::is_directory(path, error)) return true;
    std::string ext = std::filesystem::path(path).extension().string();
    std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char ch) { return std::tolower(ch); });
    if (ext == ".dcm" || ext == ".dicom") return true;
    std::ifstream in(path, std::ios::binary);
    char preamble[132] = {};
    return in.read(preamble, sizeof preamble) && std::memcmp(preamble + 128, "DICM", 4) == 0;
}

namespace {

std::vector<DicomSeries> list_series(const std::string& path, const std::set<std::string>& skip, Note* note)
{
    const Scan scan(path, skip, note);
    std::vector<DicomSeries> all = series_of(scan, path);
    for (DicomSeries& s : all) {
        try {
            (void)stack(scan, s, path);
        } catch (const InputError& e) {
            s.problem = e.what();
            if (s.problem.starts_with(path + ": ")) s.problem.erase(0, path.size() + 2); // the listing names the path
        }
    }
    return all;
}

Volume read_series(const std::string& path, const std::string& series, const std::set<std::string>& skip, Note* note)
{
    const Scan scan(path, skip, note);
    const std::vector<DicomSeries> all = series_of(scan, path);
    const DicomSeries& s = pick(all, series, path);
    const Stack geometry = stack(scan, s, path);
    const std::int64_t slice_voxels = s.size[0] * s.size[1];
    if (note == nullptr) {
        log::info("{}: reading series {} ({} {} slices of {}x{})", path, s.number, s.size[2], s.modality, s.size[0], s.size[1]);
        if (geometry.moved_mm > 1e-4)
            log::info("{}: series {}: slices placed on an even grid of {:.4f} mm; the furthest, {}, moved {:.3f} mm "
                      "(rounded header positions)",
                      path, s.number, geometry.index_to_world.col(2).head<3>().norm(), geometry.moved_file, geometry.moved_mm);
    }

    Volume v;
    v.source = path;
    v.dims = s.size;
    v.index_to_world = geometry.index_to_world;
    std::vector<double> slope, intercept;
    std::vector<char> pixels;
    for (std::size_t k = 0; k < geometry.slices.size(); ++k) {
        const std::string& file = geometry.slices[k].file;
        if (note != nullptr) note->set(file, false);
        gdcm::ImageReader reader;
        reader.SetFileName(file.c_str());
        if (!reader.Read()) throw file_error(file, "cannot be read as a DICOM image");
        const gdcm::Image& image = reader.GetImage();
        const unsigned int* dims = image.GetDimensions();
        if (image.GetNumberOfDimensions() > 2 && dims[2] > 1)
            throw file_error(file, "holds " + std::to_string(dims[2]) + " frames; a series of single-frame images is read");
        if (dims[0] != s.size[0] || dims[1] != s.size[1])
            throw file_error(file, "its pixel data is " + std::to_string(dims[0]) + "x" + std::to_string(dims[1]) +
                                       ", not the " + std::to_string(s.size[0]) + "x" + std::to_string(s.size[1]) +
                                       " its header says");
        const gdcm::PixelFormat& pf = image.GetPixelFormat();
        if (pf.GetSamplesPerPixel() != 1) throw file_error(file, "is a colour image; a scan series is greyscale");
        const ScalarType type = scalar_type(pf, file);
        if (k == 0) {
            v.type = type;
            check_allocation(path, static_cast<std::uint64_t>(slice_voxels * s.size[2]), scalar_size(type));
            v.data.resize(static_cast<std::size_t>(slice_voxels * s.size[2]) * scalar_size(type));
        } else if (type != v.type) {
            throw file_error(path, "series " + std::to_string(s.number) + " mixes pixel types (" +
                                       scalar_name(v.type) + " and " + scalar_name(type) + " in " + file + ")");
        }
        const std::size_t bytes = static_cast<std::size_t>(slice_voxels) * scalar_size(type);
        if (image.GetBufferLength() != bytes)
            throw file_error(file, "its decoded pixel data is " + std::to_string(image.GetBufferLength()) +
                                       " bytes, not the " + std::to_string(bytes) + " its header describes");
        pixels.resize(bytes);
        if (!image.GetBuffer(pixels.data()))
            throw file_error(file, std::string("cannot decode its pixel data (transfer syntax ") +
                                       gdcm::TransferSyntax::GetTSString(image.GetTransferSyntax()) + ")");
        std::memcpy(v.data.data() + k * bytes, pixels.data(), bytes);
        slope.push_back(image.GetSlope());
        intercept.push_back(image.GetIntercept());
    }
    const bool one_scale = std::all_of(slope.begin(), slope.end(), [&](double a) { return a == slope.front(); }) &&
                           std::all_of(intercept.begin(), intercept.end(), [&](double b) { return b == intercept.front(); });
    if (one_scale) {
        v.scale_slope = slope.front();
        v.scale_intercept = intercept.front();
    } else {
        // Slices scaled differently (PET, some MR): keep the scaled values themselves.
        Volume scaled = v;
        scaled.type = ScalarType::f32;
        scaled.data.resize(static_cast<std::size_t>(v.voxel_count()) * sizeof(float));
        for (std::int64_t n = 0; n < v.voxel_count(); ++n) {
            const std::size_t k = static_cast<std::size_t>(n / slice_voxels);
            const float value = static_cast<float>(slope[k] * v.stored(n) + intercept[k]);
            std::memcpy(scaled.data.data() + n * sizeof(float), &value, sizeof value);
        }
        if (note == nullptr) log::info("{}: slices carry different rescale slopes or intercepts; read as scaled float values", path);
        v = std::move(scaled);
    }
    validate(v);
    return v;
}

/// Runs `work` in a child first (see the header comment) and says how GDCM failed, on which file.
/// What the child refused is refused here with the child's message: the run here must not be
/// trusted to refuse it the same way (GDCM may throw in one code path and abort in another). A
/// file of a folder that GDCM cannot even list (a damaged DICOMDIR beside the images) is skipped
/// with a warning, and the child runs again without it. Returns the files skipped.
template <class Work> std::set<std::string> checked_in_child(const std::string& path, Work&& work)
{
    std::error_code error;
    const bool folder = std::filesystem::is_directory(path, error);
    std::uint64_t bytes = 0;
    if (folder) {
        for (const auto& entry : std::filesystem::recursive_directory_iterator(path, error))
            if (entry.is_regular_file(error)) bytes += entry.file_size(error);
    } else {
        bytes = std::filesystem::file_size(path, error);
    }
    const ChildLimits limits{memory_limit_bytes(), 10.0 + 0.2 * static_cast<double>(bytes >> 20), true};
    std::set<std::string> skip;
    for (;;) {
        Note note;
        const ChildOutcome outcome = run_in_child(
            [&] {
                try {
                    work(skip, &note);
                } catch (const InputError&) {
                    throw;
                } catch (const std::exception& e) {
                    throw file_error(note.file().empty() ? path : note.file(), std::string("GDCM failed on it: ") + e.what());
                }
            },
            limits);
        const std::string where = note.file().empty() ? path : note.file();
        std::string problem;
        switch (outcome.kind) {
        case ChildOutcome::Kind::ok: return skip;
        case ChildOutcome::Kind::failed: throw InputError(outcome.message);
        case ChildOutcome::Kind::out_of_memory:
            problem = "reading it needs more than the memory limit of " + std::to_string(memory_limit_bytes() >> 20) +
                      " MiB (corrupt, or set --max-memory-mb to raise it)";
            break;
        case ChildOutcome::Kind::timed_out:
            problem = "GDCM did not finish reading it within " + std::to_string(static_cast<int>(limits.seconds)) +
                      " s (a corrupt file?)";
            break;
        case ChildOutcome::Kind::crashed:
            problem = "not a readable DICOM file: GDCM's reader crashed on it (" + signal_name(outcome.signal) +
                      "; the file is corrupt or truncated)";
            break;
        }
        if (!folder || !note.header() || where == path || skip.size() >= 1000) throw file_error(where, problem);
        log::warn("{}: skipped: {}", where, problem);
        skip.insert(where);
    }
}

} // namespace

std::vector<DicomSeries> list_dicom_series(const std::string& path)
{
    const std::set<std::string> skip = checked_in_child(
        path, [&](const std::set<std::string>& s, Note* note) { (void)list_series(path, s, note); });
    return list_series(path, skip, nullptr);
}

Volume read_dicom(const std::string& path, const std::string& series)
{
    const std::set<std::string> skip = checked_in_child(
        path, [&](const std::set<std::string>& s, Note* note) { (void)read_series(path, series, s, note); });
    return read_series(path, series, skip, nullptr);
}

} // namespace vox::io
