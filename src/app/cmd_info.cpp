// voxsculpt info: what a volume, label grid or mesh file holds. The JSON form is the reference;
// the text form prints the same fields.

#include "app/commands.hpp"
#include "core/error.hpp"
#include "io/dicom_reader.hpp"
#include "io/file_bytes.hpp"
#include "io/nrrd_image.hpp"
#include "io/segmentation.hpp"
#include "io/mesh.hpp"
#include "io/mesh_info.hpp"
#include "io/object_import.hpp"
#include "io/volume_reader.hpp"

#include <CLI/CLI.hpp>
#include <Eigen/Geometry>
#include <nlohmann/json.hpp>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <iostream>
#include <limits>
#include <map>

namespace vox::app {
namespace {

// Insertion order: fields print in a sensible order and labels in numeric order.
using json = nlohmann::ordered_json;

json vec(const Eigen::Vector3d& v) { return json::array({v.x(), v.y(), v.z()}); }

json matrix(const Eigen::Matrix4d& m)
{
    json rows = json::array();
    for (int r = 0; r < 4; ++r) rows.push_back({m(r, 0), m(r, 1), m(r, 2), m(r, 3)});
    return rows;
}

/// World bounding box (mm) of the voxel boxes with indices in [lo, hi]: the 8 corners of
/// [lo - 0.5, hi + 0.5] mapped through the index-to-world transform.
json world_bbox(const Eigen::Matrix4d& t, const Eigen::Vector3d& lo, const Eigen::Vector3d& hi)
{
    Eigen::Vector3d mn = Eigen::Vector3d::Constant(std::numeric_limits<double>::infinity());
    Eigen::Vector3d mx = -mn;
    for (int c = 0; c < 8; ++c) {
        const Eigen::Vector3d ijk((c & 1 ? hi.x() + 0.5 : lo.x() - 0.5), (c & 2 ? hi.y() + 0.5 : lo.y() - 0.5),
                                  (c & 4 ? hi.z() + 0.5 : lo.z() - 0.5));
        const Eigen::Vector3d w = (t * ijk.homogeneous()).head<3>();
        mn = mn.cwiseMin(w);
        mx = mx.cwiseMax(w);
    }
    return {{"min", vec(mn)}, {"max", vec(mx)}};
}

json volume_info(const io::Volume& v, const std::string& path)
{
    // A label map (whole numbers, at most k_label_values of them) lists its labels; anything else
    // (a CT's Hounsfield units, an MR's intensities) its values' spread: a list of thousands of
    // "labels" describes nothing.
    constexpr std::size_t k_label_values = 256;
    std::map<double, std::uint64_t> counts;
    double lo = std::numeric_limits<double>::infinity(), hi = -lo;
    std::uint64_t nonzero = 0;
    bool integral = true;
    // Every voxel up to a million, else an even sample of a million: the percentiles' resolution.
    const std::int64_t stride = std::max<std::int64_t>(1, v.voxel_count() / 1000000);
    std::vector<double> sample;
    for (std::int64_t n = 0; n < v.voxel_count(); ++n) {
        const double s = v.stored(n);
        lo = std::min(lo, s);
        hi = std::max(hi, s);
        if (s != 0.0) ++nonzero;
        if (integral && counts.size() <= k_label_values) ++counts[s];
        if (s != static_cast<double>(static_cast<std::int64_t>(s))) integral = false;
        if (n % stride == 0) sample.push_back(v.scaled(n));
    }
    json j{{"file", path},
           {"kind", "volume"},
           {"scalar_type", io::scalar_name(v.type)},
           {"dimensions", {v.dims[0], v.dims[1], v.dims[2]}},
           {"spacing_mm", vec(v.spacing())},
           {"index_to_world", matrix(v.index_to_world)},
           {"world_bbox_mm", world_bbox(v.index_to_world, Eigen::Vector3d::Zero(),
                                        Eigen::Vector3d(v.dims[0] - 1, v.dims[1] - 1, v.dims[2] - 1))},
           {"active_voxels", nonzero},
           {"stored_range", {lo, hi}},
           {"scaling", {{"slope", v.scale_slope}, {"intercept", v.scale_intercept}}}};
    if (integral && counts.size() <= k_label_values) {
        json hist = json::object();
        for (const auto& [value, n] : counts)
            if (value != 0.0) hist[std::to_string(static_cast<std::int64_t>(value))] = n;
        j["labels"] = hist;
    } else if (!sample.empty()) {
        std::sort(sample.begin(), sample.end());
        json percentiles = json::object();
        for (const int p : {1, 5, 25, 50, 75, 95, 99})
            percentiles[std::to_string(p)] = sample[static_cast<std::size_t>(std::llround(0.01 * p * static_cast<double>(sample.size() - 1)))];
        const double a = v.scale_slope * lo + v.scale_intercept, b = v.scale_slope * hi + v.scale_intercept;
        j["values"] = {{"range", {std::min(a, b), std::max(a, b)}}, // scaled: Hounsfield units for a CT
                       {"percentiles", percentiles},
                       {"sampled_voxels", sample.size()}};
    }
    return j;
}

/// A 3D Slicer segmentation: its grid and its segments (name, ID, colour, layer, label value and
/// voxels), numbered in file order.
json segmentation_info(const std::string& path)
{
    const std::vector<io::Segment> segments = io::read_segments(path);
    const io::NrrdImage image = io::read_nrrd_image(path, true);
    const io::Volume& v = image.layers.front();
    json list = json::array();
    for (const io::Segment& s : segments) {
        std::uint64_t voxels = 0;
        if (s.layer < static_cast<int>(image.layers.size())) {
            const io::Volume& layer = image.layers[static_cast<std::size_t>(s.layer)];
            for (std::int64_t n = 0; n < layer.voxel_count(); ++n) voxels += layer.stored(n) == s.label_value;
        }
        list.push_back({{"name", s.name},
                        {"id", s.id},
                        {"color", vec(s.color)},
                        {"layer", s.layer},
                        {"label_value", s.label_value},
                        {"voxels", voxels}});
    }
    return {{"file", path},
            {"kind", "segmentation"},
            {"dimensions", {v.dims[0], v.dims[1], v.dims[2]}},
            {"spacing_mm", vec(v.spacing())},
            {"index_to_world", matrix(v.index_to_world)},
            {"world_bbox_mm", world_bbox(v.index_to_world, Eigen::Vector3d::Zero(),
                                         Eigen::Vector3d(v.dims[0] - 1, v.dims[1] - 1, v.dims[2] - 1))},
            {"layers", image.layers.size()},
            {"segments", list}};
}

/// The series of a DICOM folder (numbered as --series picks them, no patient identifiers), and the
/// volume of the one picked, or of the only one.
json dicom_info(const std::string& path, const std::string& pick)
{
    const std::vector<io::DicomSeries> all = io::list_dicom_series(path);
    json list = json::array();
    for (const io::DicomSeries& s : all) {
        list.push_back({{"number", s.number},
                        {"uid", s.uid},
                        {"description", s.description},
                        {"modality", s.modality},
                        {"size", {s.size[0], s.size[1], s.size[2]}}});
        // A series that cannot be read is still listed, with why: info describes, it does not refuse.
        if (!s.problem.empty()) list.back()["cannot_import"] = s.problem;
    }
    json j{{"file", path}, {"kind", "DICOM"}, {"series", list}};
    const io::DicomSeries* picked = all.size() == 1 && pick.empty() ? &all.front() : nullptr;
    for (const io::DicomSeries& s : all)
        if (!pick.empty() && (s.uid == pick || std::to_string(s.number) == pick)) picked = &s;
    if (!pick.empty() && picked == nullptr) (void)io::read_dicom(path, pick); // names the series that is not there
    if (picked != nullptr && picked->problem.empty()) {
        j["volume"] = volume_info(io::read_dicom(path, std::to_string(picked->number)), path);
        j["volume"].erase("file");
    }
    return j;
}

json vdb_info(const std::string& path)
{
    io::check_input_file(path);
    const grid::LabelGrid g = grid::LabelGrid::load(path);
    const grid::IndexBox box = g.index_bounds();
    json hist = json::object();
    for (const auto& [label, n] : g.label_histogram()) hist[std::to_string(label)] = n;
    json j{{"file", path},
           {"kind", "label grid"},
           {"scalar_type", "int32"},
           {"spacing_mm", vec(g.voxel_size())},
           {"index_to_world", matrix(g.index_to_world())},
           {"active_voxels", g.active_voxel_count()},
           {"labels", hist}};
    if (!box.empty()) {
        const Eigen::Vector3i d = box.max - box.min + Eigen::Vector3i::Ones();
        j["dimensions"] = {d.x(), d.y(), d.z()};
        j["index_bbox"] = {{"min", {box.min.x(), box.min.y(), box.min.z()}},
                           {"max", {box.max.x(), box.max.y(), box.max.z()}}};
        j["world_bbox_mm"] = world_bbox(g.index_to_world(), box.min.cast<double>(), box.max.cast<double>());
    }
    const std::string source = g.metadata("source");
    if (!source.empty()) j["source"] = source;
    return j;
}

json mesh_info_json(const std::string& path, double mm_per_unit)
{
    const io::MeshInfo m = io::mesh_info(io::read_mesh(path, mm_per_unit));
    return {{"file", path},
            {"kind", "mesh"},
            {"vertices", m.vertices},
            {"faces", m.triangles},
            {"boundary_edges", m.boundary_edges},
            {"non_manifold_edges", m.non_manifold_edges},
            {"closed", m.closed},
            {"components", m.components},
            {"consistently_oriented", m.consistently_oriented},
            {"area_mm2", m.area_mm2},
            // An open mesh encloses no well-defined volume.
            {"enclosed_volume_mm3", m.closed ? json(m.enclosed_volume_mm3) : json(nullptr)},
            {"world_bbox_mm", {{"min", vec(m.bbox_min)}, {"max", vec(m.bbox_max)}}}};
}

/// A value for people: numbers with 7 significant digits, arrays and objects inline.
std::string human(const json& v)
{
    if (v.is_number_float()) {
        char buffer[32];
        std::snprintf(buffer, sizeof buffer, "%.7g", v.get<double>());
        return buffer;
    }
    if (v.is_array()) {
        std::string out = "[";
        for (std::size_t i = 0; i < v.size(); ++i) out += (i ? ", " : "") + human(v[i]);
        return out + "]";
    }
    if (v.is_object()) {
        std::string out;
        for (const auto& [key, item] : v.items()) out += (out.empty() ? "" : ", ") + key + ": " + human(item);
        return out;
    }
    return v.is_string() ? v.get<std::string>() : v.dump();
}

void print_text(const json& j)
{
    for (const auto& [key, value] : j.items()) {
        if (key == "labels") {
            std::printf("labels (label: voxels):\n");
            for (const auto& [label, n] : value.items()) std::printf("  %s: %s\n", label.c_str(), n.dump().c_str());
        } else if (key == "values") {
            std::printf("values (scaled; not labels): range %s, percentiles 1 / 5 / 25 / 50 / 75 / 95 / 99: ", human(value["range"]).c_str());
            const char* between = "";
            for (const char* p : {"1", "5", "25", "50", "75", "95", "99"}) {
                std::printf("%s%s", between, human(value["percentiles"][p]).c_str());
                between = " / ";
            }
            std::printf(" (of %s voxels)\n", value["sampled_voxels"].dump().c_str());
        } else if (key == "series") {
            std::printf("series (number: modality columns x rows x slices, description, UID):\n");
            for (const json& one : value) {
                std::printf("  %s: %s %sx%sx%s \"%s\" %s\n", one["number"].dump().c_str(),
                            one["modality"].get<std::string>().c_str(), one["size"][0].dump().c_str(),
                            one["size"][1].dump().c_str(), one["size"][2].dump().c_str(),
                            one["description"].get<std::string>().c_str(), one["uid"].get<std::string>().c_str());
                if (one.contains("cannot_import"))
                    std::printf("     cannot import: %s\n", one["cannot_import"].get<std::string>().c_str());
            }
        } else if (key == "segments") {
            std::printf("segments (name, ID, layer, label value, voxels, colour):\n");
            for (const json& one : value)
                std::printf("  %s, %s, layer %s, value %s, %s voxels, colour %s\n", one["name"].get<std::string>().c_str(),
                            one["id"].get<std::string>().c_str(), one["layer"].dump().c_str(), one["label_value"].dump().c_str(),
                            one["voxels"].dump().c_str(), human(one["color"]).c_str());
        } else if (key == "volume") {
            std::printf("volume of the series read:\n");
            print_text(value);
        } else if (key == "index_to_world") {
            std::printf("index_to_world:\n");
            for (const auto& row : value) std::printf("  %s\n", human(row).c_str());
        } else {
            std::printf("%s: %s\n", key.c_str(), human(value).c_str());
        }
    }
    if (j.contains("kind") && j["kind"] == "volume" && !j.contains("labels"))
        std::printf("labels: not listed (more than 256 distinct values, or values that are not integers: the values above)\n");
}

} // namespace

void add_info_command(CLI::App& app)
{
    struct Args {
        std::string input;
        bool as_json = false;
        double mm_per_unit = 1.0;
        std::string series;
    };
    auto args = std::make_shared<Args>();
    CLI::App* cmd = app.add_subcommand("info", "Describe a volume, DICOM folder, Slicer segmentation, .vdb label grid or mesh file");
    cmd->add_option("file", args->input, "The file to describe")->required();
    cmd->add_flag("--json", args->as_json, "Print JSON instead of text");
    cmd->add_option("--scale", args->mm_per_unit, "Meshes: millimetres per file unit (default 1)")
        ->check(CLI::PositiveNumber);
    cmd->add_option("--series", args->series, "DICOM folders: also describe this series' volume (its number or UID)");
    cmd->callback([args] {
        const std::string& p = args->input;
        json j;
        if (io::is_mesh_path(p))
            j = mesh_info_json(p, args->mm_per_unit);
        else if (p.size() > 4 && p.compare(p.size() - 4, 4, ".vdb") == 0)
            j = vdb_info(p);
        else if (io::is_segmentation_path(p))
            j = segmentation_info(p);
        else if (io::is_volume_path(p))
            j = volume_info(io::read_volume(p), p);
        else if (io::is_dicom_path(p))
            j = dicom_info(p, args->series);
        else
            j = volume_info(io::read_volume(p), p); // names what it expected
        if (!args->series.empty() && j["kind"] != "DICOM")
            throw file_error(p, "--series picks a series of a DICOM folder; this is not one");
        if (args->as_json)
            std::cout << j.dump(2, ' ', false, json::error_handler_t::replace) << '\n'; // a DICOM description may be Latin-1
        else
            print_text(j);
    });
}

} // namespace vox::app
