#include "io/segmentation.hpp"

#include "core/error.hpp"
#include "core/log.hpp"
#include "io/nrrd_image.hpp"
#include "io/text_parsing.hpp"

#include <nlohmann/json.hpp>

#include <algorithm>
#include <cmath>
#include <map>
#include <sstream>

namespace vox::io {
namespace {

const std::string* find(const std::map<std::string, std::string>& pairs, const std::string& key)
{
    const auto it = pairs.find(key);
    return it == pairs.end() ? nullptr : &it->second;
}

long whole(const std::string& path, const std::string& key, const std::string& text, long lo, long hi)
{
    const std::string t(detail::trim(text));
    char* end = nullptr;
    const long v = std::strtol(t.c_str(), &end, 10);
    if (t.empty() || end != t.c_str() + t.size() || v < lo || v > hi)
        throw file_error(path, key + " '" + detail::printable(text) + "' is not a whole number from " +
                                   std::to_string(lo) + " to " + std::to_string(hi));
    return v;
}

std::string names_of(const std::vector<Segment>& all)
{
    std::string out;
    for (const Segment& s : all) out += (out.empty() ? "" : ", ") + s.name + (s.name == s.id ? "" : " (" + s.id + ")");
    return out;
}

} // namespace

bool is_segmentation_path(const std::string& path)
{
    const std::string p = detail::lower_case(path);
    return p.size() > 9 && p.compare(p.size() - 9, 9, ".seg.nrrd") == 0;
}

std::vector<Segment> read_segments(const std::string& path)
{
    const std::map<std::string, std::string> pairs = read_nrrd_pairs(path);
    std::vector<Segment> out;
    for (int n = 0; n < 100000; ++n) {
        const std::string prefix = "Segment" + std::to_string(n) + "_";
        const std::string* id = find(pairs, prefix + "ID");
        if (id == nullptr) break;
        Segment s;
        s.id = *id;
        const std::string* name = find(pairs, prefix + "Name");
        s.name = name != nullptr && !name->empty() ? *name : s.id;
        if (const std::string* color = find(pairs, prefix + "Color")) {
            std::istringstream in(*color);
            if (!(in >> s.color.x() >> s.color.y() >> s.color.z()) || !(in >> std::ws).eof() ||
                (s.color.array() < 0.0).any() || (s.color.array() > 1.0).any())
                throw file_error(path, prefix + "Color '" + detail::printable(*color) + "' is not three numbers from 0 to 1");
        }
        if (const std::string* value = find(pairs, prefix + "LabelValue"))
            s.label_value = static_cast<std::int32_t>(whole(path, prefix + "LabelValue", *value, 1, 2147483647));
        else // Slicer before 4.11 wrote none (a layer per segment, its voxels 1); a newer file should
            log::warn("{}: segment '{}' has no {}LabelValue: its voxels are read as those of value 1 in its layer", path, s.name, prefix);
        s.layer = n; // Slicer before 4.11 kept each segment in a layer of its own
        if (const std::string* layer = find(pairs, prefix + "Layer"))
            s.layer = static_cast<int>(whole(path, prefix + "Layer", *layer, 0, 100000));
        if (const std::string* tags = find(pairs, prefix + "Tags")) s.tags = *tags;
        out.push_back(std::move(s));
    }
    if (out.empty())
        throw file_error(path, "names no segment (no Segment0_ID key): not a 3D Slicer segmentation; read it as a .nrrd label map");
    return out;
}

std::vector<Segment> pick_segments(const std::vector<Segment>& all, const std::vector<std::string>& names,
                                   const std::string& path)
{
    if (names.empty()) return all;
    std::vector<Segment> out;
    for (const std::string& name : names) {
        std::vector<const Segment*> found;
        for (const Segment& s : all)
            if (s.name == name || s.id == name) found.push_back(&s);
        if (found.empty())
            throw file_error(path, "has no segment named '" + name + "' (its segments: " + names_of(all) + ")");
        if (found.size() > 1)
            throw file_error(path, std::to_string(found.size()) + " segments are named '" + name +
                                       "': pick them by ID (its segments: " + names_of(all) + ")");
        out.push_back(*found.front());
    }
    return out;
}

grid::LabelGrid read_segmentation(const std::string& path, const std::vector<std::string>& names)
{
    const std::vector<Segment> picked = pick_segments(read_segments(path), names, path);
    const NrrdImage image = read_nrrd_image(path, true);
    for (const Segment& s : picked)
        if (s.layer >= static_cast<int>(image.layers.size()))
            throw file_error(path, "segment '" + s.name + "' is in layer " + std::to_string(s.layer) + ", but the file has " +
                                       std::to_string(image.layers.size()) + " layer(s)");
    const Volume& first = image.layers.front();
    grid::LabelGrid out(first.index_to_world);
    out.set_metadata("source", path);
    out.set_metadata("scan_dims", std::to_string(first.dims[0]) + " " + std::to_string(first.dims[1]) + " " +
                                      std::to_string(first.dims[2]));
    out.set_metadata("segments", segment_metadata(picked));
    // In pick order, so that where segments overlap the later one's label stays.
    for (std::size_t k = 0; k < picked.size(); ++k) {
        const Volume& layer = image.layers[static_cast<std::size_t>(picked[k].layer)];
        const double value = picked[k].label_value;
        std::int64_t n = 0;
        for (std::int32_t z = 0; z < layer.dims[2]; ++z)
            for (std::int32_t y = 0; y < layer.dims[1]; ++y)
                for (std::int32_t x = 0; x < layer.dims[0]; ++x, ++n)
                    if (layer.stored(n) == value) out.set({x, y, z}, static_cast<std::int32_t>(k + 1));
    }
    if (out.active_voxel_count() == 0)
        throw file_error(path, "the segments picked (" + names_of(picked) + ") hold no voxel");
    return out;
}

std::string segment_metadata(const std::vector<Segment>& picked)
{
    nlohmann::json list = nlohmann::json::array();
    for (std::size_t k = 0; k < picked.size(); ++k) {
        const Segment& s = picked[k];
        list.push_back({{"label", k + 1},
                        {"id", s.id},
                        {"name", s.name},
                        {"color", {s.color.x(), s.color.y(), s.color.z()}},
                        {"tags", s.tags}});
    }
    // A name in another encoding than UTF-8 (found by fuzzing) keeps its readable part.
    return list.dump(-1, ' ', false, nlohmann::json::error_handler_t::replace);
}

std::vector<std::pair<std::int32_t, Segment>> segments_of(const grid::LabelGrid& labels)
{
    std::vector<std::pair<std::int32_t, Segment>> out;
    const std::string text = labels.metadata("segments");
    if (text.empty()) return out;
    const nlohmann::json list = nlohmann::json::parse(text, nullptr, false);
    if (!list.is_array()) return out; // not ours: written by something else; the labels still stand
    for (const nlohmann::json& item : list) {
        if (!item.is_object() || !item.contains("label") || !item["label"].is_number_integer()) continue;
        Segment s;
        s.id = item.value("id", std::string());
        s.name = item.value("name", s.id);
        s.tags = item.value("tags", std::string());
        if (item.contains("color") && item["color"].is_array() && item["color"].size() == 3)
            for (int c = 0; c < 3; ++c) s.color[c] = item["color"][static_cast<std::size_t>(c)].is_number() ? item["color"][static_cast<std::size_t>(c)].get<double>() : 0.5;
        out.emplace_back(item["label"].get<std::int32_t>(), std::move(s));
    }
    return out;
}

} // namespace vox::io
