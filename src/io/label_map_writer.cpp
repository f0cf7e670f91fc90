#include "io/label_map_writer.hpp"

#include "core/atomic_file.hpp"
#include "core/error.hpp"
#include "core/label_palette.hpp"
#include "io/nifti_writer.hpp"
#include "io/segmentation.hpp"
#include "io/text_parsing.hpp"

#include <zlib.h>

#include <array>
#include <cstring>
#include <fstream>
#include <optional>
#include <limits>
#include <map>
#include <sstream>

namespace vox::io {
namespace {

bool ends_with(const std::string& s, const std::string& suffix)
{
    return s.size() >= suffix.size() && s.compare(s.size() - suffix.size(), suffix.size(), suffix) == 0;
}

std::string gzip(const std::vector<std::byte>& data, const std::string& path)
{
    z_stream z{};
    if (deflateInit2(&z, 6, Z_DEFLATED, 15 + 16, 8, Z_DEFAULT_STRATEGY) != Z_OK) throw file_error(path, "zlib could not start");
    std::string out(deflateBound(&z, static_cast<uLong>(data.size())), '\0');
    z.next_in = reinterpret_cast<Bytef*>(const_cast<std::byte*>(data.data()));
    z.avail_in = static_cast<uInt>(data.size());
    z.next_out = reinterpret_cast<Bytef*>(out.data());
    z.avail_out = static_cast<uInt>(out.size());
    const int status = deflate(&z, Z_FINISH);
    out.resize(z.total_out);
    deflateEnd(&z);
    if (status != Z_STREAM_END) throw file_error(path, "zlib could not compress the voxels");
    return out;
}

std::string vector_text(const Eigen::Vector3d& v)
{
    std::ostringstream out;
    out.precision(17);
    out << "(" << v.x() << "," << v.y() << "," << v.z() << ")";
    return out.str();
}

/// A NRRD file: the header (LPS space, gzip), `pairs` as "key:=value" lines, then the voxels.
void write_nrrd(const Volume& v, const std::vector<std::pair<std::string, std::string>>& pairs,
                const std::filesystem::path& path)
{
    if (v.data.size() > std::numeric_limits<uInt>::max()) throw file_error(path.string(), "too many voxels for one gzip block");
    const char* type = v.type == ScalarType::u8 ? "uint8" : v.type == ScalarType::i16 ? "int16" : "int32";
    std::ostringstream h;
    h << "NRRD0004\n# Complete NRRD file format specification at:\n# http://teem.sourceforge.net/nrrd/format.html\n"
      << "type: " << type << "\ndimension: 3\nspace: left-posterior-superior\n"
      << "sizes: " << v.dims[0] << " " << v.dims[1] << " " << v.dims[2] << "\n"
      << "space directions: " << vector_text(v.index_to_world.block<3, 1>(0, 0)) << " "
      << vector_text(v.index_to_world.block<3, 1>(0, 1)) << " " << vector_text(v.index_to_world.block<3, 1>(0, 2)) << "\n"
      << "kinds: domain domain domain\nendian: little\nencoding: gzip\n"
      << "space origin: " << vector_text(v.index_to_world.block<3, 1>(0, 3)) << "\n";
    for (const auto& [key, value] : pairs) h << key << ":=" << value << "\n";
    h << "\n";
    const std::string zipped = gzip(v.data, path.string());
    write_atomically(path, [&](const std::filesystem::path& tmp) {
        std::ofstream out(tmp, std::ios::binary);
        out << h.str();
        out.write(zipped.data(), static_cast<std::streamsize>(zipped.size()));
        if (!out) throw file_error(path.string(), "cannot be written");
    });
}

/// Slicer's keys for one layer of segments, each label one segment (its extent in the grid written).
std::vector<std::pair<std::string, std::string>> segmentation_pairs(const grid::LabelGrid& labels, const grid::Coord& offset)
{
    std::map<std::int32_t, Segment> by_label;
    for (auto& [label, segment] : segments_of(labels)) by_label[label] = segment;
    std::map<std::int32_t, grid::IndexBox> extent;
    labels.for_each_active([&](const grid::Coord& c, std::int32_t label) {
        grid::IndexBox& box = extent[label];
        const grid::Coord at = c - offset;
        if (box.empty()) {
            box.min = box.max = at;
        } else {
            box.min = box.min.cwiseMin(at);
            box.max = box.max.cwiseMax(at);
        }
    });
    for (const auto& [label, box] : extent) {
        if (by_label.count(label)) continue;
        Segment s;
        s.id = "Segment_" + std::to_string(label);
        s.name = "label " + std::to_string(label);
        s.color = label_color(label);
        by_label[label] = s;
    }
    std::vector<std::pair<std::string, std::string>> pairs{
        {"Segmentation_ContainedRepresentationNames", "Binary labelmap|"},
        {"Segmentation_MasterRepresentation", "Binary labelmap"},
        {"Segmentation_ReferenceImageExtentOffset", "0 0 0"}};
    int n = 0;
    for (const auto& [label, s] : by_label) {
        const std::string p = "Segment" + std::to_string(n++) + "_";
        std::ostringstream color, box_text;
        color << s.color.x() << " " << s.color.y() << " " << s.color.z();
        const auto it = extent.find(label);
        if (it == extent.end()) {
            box_text << "0 -1 0 -1 0 -1"; // every voxel cut away: Slicer's empty extent
        } else {
            const grid::IndexBox& b = it->second;
            box_text << b.min.x() << " " << b.max.x() << " " << b.min.y() << " " << b.max.y() << " " << b.min.z() << " " << b.max.z();
        }
        pairs.insert(pairs.end(), {{p + "Color", color.str()},
                                   {p + "ColorAutoGenerated", "0"},
                                   {p + "Extent", box_text.str()},
                                   {p + "ID", s.id},
                                   {p + "LabelValue", std::to_string(label)},
                                   {p + "Layer", "0"},
                                   {p + "Name", s.name},
                                   {p + "NameAutoGenerated", "0"},
                                   {p + "Tags", s.tags.empty() ? "|" : s.tags}});
    }
    return pairs;
}

} // namespace

bool is_label_map_path(const std::string& path)
{
    const std::string p = detail::lower_case(path);
    return ends_with(p, ".nrrd") || ends_with(p, ".nii") || ends_with(p, ".nii.gz");
}

void write_label_map(const grid::LabelGrid& labels, const std::filesystem::path& path)
{
    const std::string name = path.string();
    if (!is_label_map_path(name)) throw file_error(name, "a label map is written as .seg.nrrd, .nrrd, .nii or .nii.gz");
    const grid::IndexBox active = labels.index_bounds();
    if (active.empty()) throw file_error(name, "there is no voxel to write");
    // The scan's grid when the voxels still lie in it (they do unless they came from elsewhere).
    grid::IndexBox box = active;
    std::istringstream scan(labels.metadata("scan_dims"));
    grid::Coord dims;
    if (scan >> dims.x() >> dims.y() >> dims.z() && (dims.array() > 0).all() && (active.min.array() >= 0).all() &&
        (active.max.array() < dims.array()).all()) {
        box.min = grid::Coord::Zero();
        box.max = dims - grid::Coord::Ones();
    }
    std::int32_t lo = 0, hi = 0;
    for (const auto& [label, count] : labels.label_histogram()) {
        lo = std::min(lo, label);
        hi = std::max(hi, label);
    }
    Volume v;
    v.source = name;
    v.dims = {box.max.x() - box.min.x() + 1, box.max.y() - box.min.y() + 1, box.max.z() - box.min.z() + 1};
    v.type = lo >= 0 && hi <= 255 ? ScalarType::u8 : lo >= -32768 && hi <= 32767 ? ScalarType::i16 : ScalarType::i32;
    Eigen::Matrix4d shift = Eigen::Matrix4d::Identity();
    shift.block<3, 1>(0, 3) = box.min.cast<double>();
    v.index_to_world = labels.index_to_world() * shift;
    if (std::optional<NiftiTransforms> nifti = NiftiTransforms::parse(labels.metadata("nifti_transforms"))) {
        nifti->qform_ras = nifti->qform_ras * shift; // the scan's own codes and qform, on this box
        v.nifti = nifti;
    }
    const std::size_t size = scalar_size(v.type);
    v.data.assign(static_cast<std::size_t>(v.voxel_count()) * size, std::byte{0});
    labels.for_each_active([&](const grid::Coord& c, std::int32_t label) {
        const grid::Coord at = c - box.min;
        const auto n = static_cast<std::size_t>(at.x() + v.dims[0] * (at.y() + v.dims[1] * static_cast<std::int64_t>(at.z())));
        const auto u8 = static_cast<std::uint8_t>(label);
        const auto i16 = static_cast<std::int16_t>(label);
        std::memcpy(v.data.data() + n * size, size == 1 ? static_cast<const void*>(&u8) : size == 2 ? static_cast<const void*>(&i16) : &label, size);
    });
    const std::string lower = detail::lower_case(name);
    if (ends_with(lower, ".nii") || ends_with(lower, ".nii.gz"))
        write_nifti(v, path);
    else
        write_nrrd(v, is_segmentation_path(name) ? segmentation_pairs(labels, box.min) : std::vector<std::pair<std::string, std::string>>{}, path);
}

} // namespace vox::io
