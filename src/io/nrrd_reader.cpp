// NRRD reader (.nrrd with attached data, .nhdr with a detached data file), after teem's format
// definition (http://teem.sourceforge.net/nrrd/format.html, magics NRRD0001 to NRRD0005):
//
// - The header is the magic line, then "<field>: <desc>" lines, "<key>:=<value>" pairs (kept for
//   the segmentation reader, io/segmentation.hpp; a repeated key keeps its last value) and
//   "#" comments, up to the first empty line; attached data starts on the byte after it. Field
//   names are matched ignoring case and spaces, as teem does ("data file" = "datafile"). Unknown
//   and repeated fields are refused: a misspelt "space directions" must not silently lose the
//   geometry.
// - World frame: "space" left-posterior-superior (LPS) is used as is; right-anterior-superior (RAS)
//   has x and y negated and left-anterior-superior (LAS) has y negated to give LPS, as ITK's
//   NrrdImageIO does (it negated x for LAS until its issue #5207 was fixed by PR #5224 in 2025;
//   we follow the corrected, anatomically right conversion). "scanner-xyz", "3D-right-handed" and a bare
//   "space dimension: 3" carry no anatomical labels: taken as LPS, which is also what ITK does.
//   Left-handed and time-varying spaces are refused.
// - "space directions" gives, per axis, the world step between neighbouring samples (spacing
//   included) or "none" for a non-spatial axis; "space origin" is the centre of the first sample.
//   Without a space, "spacings" gives axis-aligned spacings and the origin is (0,0,0) ("axis mins"
//   are ignored).
// - Non-spatial axes (direction "none", spacing nan, or a non-domain kind) of size 1 are dropped; a
//   non-spatial axis with more samples (vector, colour, time series) is refused. Two spatial axes
//   are read as a single slice (third axis along the normal, spacing 1 mm).
// - Encodings raw, gzip (gz) and ascii (text, txt); "line skip" skips lines of the data file, then
//   "byte skip" skips bytes (of the decompressed stream for gzip, as teem does); byte skip -1
//   (data at the end) is accepted with raw data only. Data longer than the header describes is
//   refused: the header then does not describe the data.

#include "core/error.hpp"
#include "core/memory_limit.hpp"
#include "io/file_bytes.hpp"
#include "io/text_parsing.hpp"
#include "io/nrrd_image.hpp"
#include "io/volume_reader.hpp"

#include <Eigen/Geometry>

#include <algorithm>
#include <bit>
#include <cctype>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <limits>
#include <map>
#include <set>
#include <string_view>

namespace vox::io {

using detail::field_double;
using detail::field_int;
using detail::HeaderFields;
using detail::printable;
using detail::trim;

namespace {

/// NRRD headers are a few hundred bytes: a header with no blank line in its first MiB is refused
/// rather than pulling binary data into memory.
constexpr std::size_t k_max_header_bytes = std::size_t{1} << 20;

enum class Encoding { raw, gzip, ascii };
enum class Space { lps, ras, las };

std::string lower(std::string_view s)
{
    std::string out(s);
    std::transform(out.begin(), out.end(), out.begin(),
                   [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
    return out;
}

/// Lower case, inner runs of blanks collapsed to one space: "Unsigned  Short" -> "unsigned short".
std::string canonical_words(std::string_view s)
{
    std::string out;
    for (const char c : trim(s)) {
        if (c == ' ' || c == '\t') {
            if (out.back() != ' ') out += ' ';
        } else {
            out += static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
        }
    }
    return out;
}

/// Splits a per-axis description into words; a parenthesised vector "(1, 0,0)" and a quoted string
/// are one word each.
std::vector<std::string_view> split_nrrd_words(std::string_view s)
{
    std::vector<std::string_view> words;
    std::size_t pos = 0;
    while (true) {
        pos = s.find_first_not_of(" \t", pos);
        if (pos == std::string_view::npos) return words;
        std::size_t end = 0;
        if (s[pos] == '(') {
            end = s.find(')', pos);
            end = end == std::string_view::npos ? s.size() : end + 1;
        } else if (s[pos] == '"') {
            end = s.find('"', pos + 1);
            end = end == std::string_view::npos ? s.size() : end + 1;
        } else {
            end = std::min(s.find_first_of(" \t", pos), s.size());
        }
        words.push_back(s.substr(pos, end - pos));
        pos = end;
    }
}

/// Field names of the format; those not used below are accepted and ignored.
const std::set<std::string, std::less<>>& known_fields()
{
    static const std::set<std::string, std::less<>> names = {"dimension",
                                                             "type",
                                                             "sizes",
                                                             "encoding",
                                                             "endian",
                                                             "space",
                                                             "spacedimension",
                                                             "spacedirections",
                                                             "spaceorigin",
                                                             "spaceunits",
                                                             "spacings",
                                                             "kinds",
                                                             "datafile",
                                                             "lineskip",
                                                             "byteskip",
                                                             "content",
                                                             "min",
                                                             "max",
                                                             "oldmin",
                                                             "oldmax",
                                                             "number",
                                                             "sampleunits",
                                                             "measurementframe",
                                                             "blocksize",
                                                             "thicknesses",
                                                             "axismins",
                                                             "axismaxs",
                                                             "centers",
                                                             "centerings",
                                                             "labels",
                                                             "units"};
    return names;
}

/// The header's fields by normalised name (lower case, no spaces), and the byte offset just past the
/// blank line that ends it (the file size when the header runs to the end of the file).
HeaderFields read_header(const std::string& path)
{
    const auto [text, whole_file] = read_file_head(path, k_max_header_bytes);

    const auto first_nl = text.find('\n');
    const std::string_view magic = trim(std::string_view(text).substr(0, std::min(first_nl, std::size_t{16})));
    if (magic.size() != 8 || magic.substr(0, 7) != "NRRD000" || magic[7] < '1' || magic[7] > '5')
        throw file_error(path,
                         "not a NRRD file: starts with " +
                             (detail::is_binary(magic) ? std::string("binary data") : "'" + printable(magic) + "'") +
                             ", expected the magic NRRD0001 to NRRD0005");

    if (first_nl == std::string::npos) throw file_error(path, "has nothing after the NRRD magic line");
    HeaderFields h;
    std::size_t pos = first_nl + 1;
    for (int line_no = 2; pos < text.size(); ++line_no) {
        auto nl = text.find('\n', pos);
        if (nl == std::string::npos && !whole_file) break;
        if (nl == std::string::npos) nl = text.size();
        std::string_view line = std::string_view(text).substr(pos, nl - pos);
        pos = std::min(nl + 1, text.size());
        if (!line.empty() && line.back() == '\r') line.remove_suffix(1);
        if (line.empty()) {
            h.end = pos;
            return h;
        }
        if (line.front() == '#') continue;
        if (detail::is_binary(line))
            throw file_error(path, "header line " + std::to_string(line_no) +
                                       " holds binary data (the header must end with a blank line before the data)");
        // "key:=value" pairs are free-form metadata; a field's ": " may come later on the line only
        // inside its description, so whichever separator comes first decides.
        const auto kv = line.find(":=");
        const auto colon = line.find(':');
        if (colon == std::string_view::npos)
            throw file_error(path, "header line " + std::to_string(line_no) + " is not '<field>: <value>' ('" +
                                       printable(line) + "')");
        if (kv == colon) {
            h.pairs[std::string(line.substr(0, kv))] = std::string(line.substr(kv + 2));
            continue;
        }
        std::string name;
        for (const char c : line.substr(0, colon))
            if (c != ' ' && c != '\t') name += static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
        if (!known_fields().contains(name))
            throw file_error(path, "unknown header field '" + printable(trim(line.substr(0, colon))) + "' on line " +
                                       std::to_string(line_no));
        if (name == "centerings") name = "centers";
        const std::string value(trim(line.substr(colon + 1)));
        if (!h.fields.emplace(name, value).second)
            throw file_error(path, "header field '" + printable(trim(line.substr(0, colon))) + "' appears twice");
        // "data file: LIST" ends the header: the data file names follow, one per line.
        if (name == "datafile" && value.rfind("LIST", 0) == 0) {
            h.end = pos;
            return h;
        }
    }
    if (!whole_file) throw file_error(path, "header has no blank line ending it in its first MiB");
    h.end = text.size();
    return h;
}

/// An integer field; NRRD integers may carry a leading '+'.
std::int64_t parse_int(const std::string& path, std::string_view field, std::string_view word)
{
    if (!word.empty() && word.front() == '+') word.remove_prefix(1);
    return field_int(path, field, word);
}

/// Parses "(x,y,z)" into exactly three finite numbers.
Eigen::Vector3d parse_vector(const std::string& path, std::string_view field, std::string_view word)
{
    if (word.size() < 2 || word.front() != '(' || word.back() != ')')
        throw file_error(path,
                         "'" + std::string(field) + "' value '" + printable(word) + "' is not a vector '(x,y,z)'");
    std::string_view inner = word.substr(1, word.size() - 2);
    std::vector<double> parts;
    while (true) {
        const auto comma = inner.find(',');
        parts.push_back(field_double(path, field, trim(inner.substr(0, comma))));
        if (comma == std::string_view::npos) break;
        inner.remove_prefix(comma + 1);
    }
    if (parts.size() != 3)
        throw file_error(path, "'" + std::string(field) + "' vector '" + printable(word) + "' has " +
                                   std::to_string(parts.size()) + " components, expected 3 for a 3-D space");
    return {parts[0], parts[1], parts[2]};
}

/// The words of a per-axis field, which must number one per axis.
std::vector<std::string_view> per_axis(const std::string& path, const HeaderFields& h, std::string_view field,
                                       const std::string& label, std::size_t dimension)
{
    const std::string* value = h.find(field);
    if (!value) return {};
    auto words = split_nrrd_words(*value);
    if (words.size() != dimension)
        throw file_error(path, "'" + label + "' has " + std::to_string(words.size()) + " values, expected " +
                                   std::to_string(dimension) + " for dimension " + std::to_string(dimension));
    return words;
}

ScalarType parse_type(const std::string& path, const std::string& text)
{
    static const std::map<std::string, ScalarType, std::less<>> types = {{"signed char", ScalarType::i8},
                                                                         {"int8", ScalarType::i8},
                                                                         {"int8_t", ScalarType::i8},
                                                                         {"uchar", ScalarType::u8},
                                                                         {"unsigned char", ScalarType::u8},
                                                                         {"uint8", ScalarType::u8},
                                                                         {"uint8_t", ScalarType::u8},
                                                                         {"short", ScalarType::i16},
                                                                         {"short int", ScalarType::i16},
                                                                         {"signed short", ScalarType::i16},
                                                                         {"signed short int", ScalarType::i16},
                                                                         {"int16", ScalarType::i16},
                                                                         {"int16_t", ScalarType::i16},
                                                                         {"ushort", ScalarType::u16},
                                                                         {"unsigned short", ScalarType::u16},
                                                                         {"unsigned short int", ScalarType::u16},
                                                                         {"uint16", ScalarType::u16},
                                                                         {"uint16_t", ScalarType::u16},
                                                                         {"int", ScalarType::i32},
                                                                         {"signed int", ScalarType::i32},
                                                                         {"int32", ScalarType::i32},
                                                                         {"int32_t", ScalarType::i32},
                                                                         {"uint", ScalarType::u32},
                                                                         {"unsigned int", ScalarType::u32},
                                                                         {"uint32", ScalarType::u32},
                                                                         {"uint32_t", ScalarType::u32},
                                                                         {"float", ScalarType::f32},
                                                                         {"double", ScalarType::f64}};
    const std::string name = canonical_words(text);
    const auto it = types.find(name);
    if (it != types.end()) return it->second;
    throw file_error(path, "unsupported type '" + printable(text) +
                               "' (supported: 8-, 16- and 32-bit integers, float, double)");
}

Encoding parse_encoding(const std::string& path, const std::string& text)
{
    const std::string e = lower(text);
    if (e == "raw") return Encoding::raw;
    if (e == "gzip" || e == "gz") return Encoding::gzip;
    if (e == "ascii" || e == "text" || e == "txt") return Encoding::ascii;
    throw file_error(path, "unsupported encoding '" + printable(text) + "' (supported: raw, gzip, ascii)");
}

Space parse_space(const std::string& path, const std::string& text)
{
    // teem accepts "left-posterior-superior", "left posterior superior", "leftposteriorsuperior", "LPS".
    std::string s;
    for (const char c : lower(text))
        if (c != '-' && c != ' ') s += c;
    if (s == "leftposteriorsuperior" || s == "lps" || s == "scannerxyz" || s == "3drighthanded") return Space::lps;
    if (s == "rightanteriorsuperior" || s == "ras") return Space::ras;
    if (s == "leftanteriorsuperior" || s == "las") return Space::las;
    throw file_error(path, "unsupported space '" + printable(text) +
                               "' (supported: left-posterior-superior, right-anterior-superior, "
                               "left-anterior-superior, scanner-xyz, 3D-right-handed)");
}

/// Kinds that describe a spatial (domain) axis; any other kind marks a range axis such as a vector.
bool is_domain_kind(std::string_view kind)
{
    const std::string k = lower(kind);
    return k == "domain" || k == "space" || k == "???" || k == "none";
}

/// Where the voxel bytes are: the file, and the offset its data section starts at (before any line
/// or byte skip).
struct DataSource {
    std::string file;
    std::uint64_t offset = 0;
    std::string what; ///< names the header (and data file) in messages
};

std::uint64_t file_size(const DataSource& src)
{
    std::error_code ec;
    const auto size = std::filesystem::file_size(src.file, ec);
    if (ec) throw file_error(src.what, "cannot read the size of '" + src.file + "': " + ec.message());
    return size;
}

std::vector<std::byte> read_range(const DataSource& src, std::uint64_t offset, std::uint64_t count)
{
    check_allocation(src.what, count, 1);
    std::vector<std::byte> out(count);
    read_file_range(src.file, offset, out.data(), count, src.what);
    return out;
}

/// The offset just past `lines` more newlines from `offset`.
std::uint64_t skip_lines(const DataSource& src, std::uint64_t offset, std::int64_t lines)
{
    std::ifstream in(src.file, std::ios::binary);
    in.seekg(static_cast<std::streamoff>(offset));
    std::vector<char> chunk(1 << 16);
    while (lines > 0) {
        in.read(chunk.data(), static_cast<std::streamsize>(chunk.size()));
        const auto got = static_cast<std::size_t>(in.gcount());
        if (got == 0) throw file_error(src.what, "'line skip' passes the end of the data");
        for (std::size_t i = 0; i < got; ++i)
            if (chunk[i] == '\n' && --lines == 0) return offset + i + 1;
        offset += got;
    }
    return offset;
}

template <class T> void store_as(const std::string& what, std::string_view word, double value, std::byte* out)
{
    if constexpr (std::is_integral_v<T>) {
        if (value != std::floor(value) || value < static_cast<double>(std::numeric_limits<T>::lowest()) ||
            value > static_cast<double>(std::numeric_limits<T>::max()))
            throw file_error(what, "ascii value '" + printable(word) + "' does not fit the integer type");
    } else if constexpr (std::is_same_v<T, float>) {
        if (std::isfinite(value) && std::abs(value) > static_cast<double>(std::numeric_limits<float>::max()))
            throw file_error(what, "ascii value '" + printable(word) + "' does not fit a float");
    }
    const T v = static_cast<T>(value);
    std::memcpy(out, &v, sizeof(T));
}

/// Parses whitespace- or comma-separated numbers into `v.data` (already sized).
void parse_ascii(const std::string& what, std::string_view text, Volume& v)
{
    const auto count = static_cast<std::size_t>(v.voxel_count());
    const std::size_t width = scalar_size(v.type);
    std::size_t n = 0;
    std::size_t pos = 0;
    while (true) {
        pos = text.find_first_not_of(" \t\r\n,", pos);
        if (pos == std::string_view::npos) break;
        const auto end = std::min(text.find_first_of(" \t\r\n,", pos), text.size());
        if (n == count)
            throw file_error(what, "ascii data holds more than the " + std::to_string(count) + " values expected");
        const std::string_view word = text.substr(pos, end - pos);
        const double value = field_double(what, "ascii data", word, true);
        std::byte* out = v.data.data() + n * width;
        switch (v.type) {
        case ScalarType::u8: store_as<std::uint8_t>(what, word, value, out); break;
        case ScalarType::i8: store_as<std::int8_t>(what, word, value, out); break;
        case ScalarType::u16: store_as<std::uint16_t>(what, word, value, out); break;
        case ScalarType::i16: store_as<std::int16_t>(what, word, value, out); break;
        case ScalarType::u32: store_as<std::uint32_t>(what, word, value, out); break;
        case ScalarType::i32: store_as<std::int32_t>(what, word, value, out); break;
        case ScalarType::f32: store_as<float>(what, word, value, out); break;
        case ScalarType::f64: store_as<double>(what, word, value, out); break;
        }
        ++n;
        pos = end;
    }
    if (n < count)
        throw file_error(what, "truncated: ascii data holds " + std::to_string(n) + " values, expected " +
                                   std::to_string(count));
}

} // namespace

std::map<std::string, std::string> read_nrrd_pairs(const std::string& path) { return read_header(path).pairs; }

Volume read_nrrd(const std::string& path) { return std::move(read_nrrd_image(path, false).layers.front()); }

NrrdImage read_nrrd_image(const std::string& path, bool layered)
{
    const HeaderFields h = read_header(path);
    auto required = [&](std::string_view field, const char* label) -> const std::string& {
        const std::string* value = h.find(field);
        if (!value) throw file_error(path, std::string("header has no '") + label + "' field");
        return *value;
    };

    const std::int64_t dimension = parse_int(path, "dimension", required("dimension", "dimension"));
    if (dimension < 1 || dimension > 16)
        throw file_error(path, "dimension " + std::to_string(dimension) + " is out of range (1 to 16)");
    const auto dim = static_cast<std::size_t>(dimension);
    Volume v;
    v.source = path;
    v.type = parse_type(path, required("type", "type"));
    const Encoding encoding = parse_encoding(path, required("encoding", "encoding"));

    required("sizes", "sizes");
    std::vector<std::int64_t> sizes;
    std::uint64_t count = 1;
    for (const auto word : per_axis(path, h, "sizes", "sizes", dim)) {
        sizes.push_back(parse_int(path, "sizes", word));
        if (sizes.back() <= 0)
            throw file_error(path, "'sizes' of axis " + std::to_string(sizes.size() - 1) + " is " +
                                       std::to_string(sizes.back()) + " (must be positive)");
        if (count > std::numeric_limits<std::uint64_t>::max() / static_cast<std::uint64_t>(sizes.back()))
            throw file_error(path, "'sizes' overflow 64-bit sizes");
        count *= static_cast<std::uint64_t>(sizes.back());
    }

    bool big_endian = false;
    if (const std::string* endian = h.find("endian")) {
        const std::string e = lower(*endian);
        if (e != "little" && e != "big")
            throw file_error(path, "endian '" + printable(*endian) + "' is not 'little' or 'big'");
        big_endian = e == "big";
    } else if (scalar_size(v.type) > 1 && encoding != Encoding::ascii) {
        throw file_error(path,
                         "header has no 'endian' field, needed for " + std::string(scalar_name(v.type)) + " data");
    }

    // Space: a named frame and/or a space dimension, which must be 3.
    const std::string* space_name = h.find("space");
    const std::string* space_dim = h.find("spacedimension");
    if (space_name && space_dim) throw file_error(path, "'space' and 'space dimension' are both given; use one");
    const Space space = space_name ? parse_space(path, *space_name) : Space::lps;
    if (space_dim && parse_int(path, "space dimension", *space_dim) != 3)
        throw file_error(path, "space dimension " + printable(*space_dim) + " is not supported (only 3)");
    const bool has_space = space_name || space_dim;
    if (has_space && h.find("spacings"))
        throw file_error(path, "'spacings' cannot be given with a space (use 'space directions')");
    if (!has_space && (h.find("spacedirections") || h.find("spaceorigin")))
        throw file_error(path, "'space directions' or 'space origin' given without 'space'");
    if (const std::string* units = h.find("spaceunits"))
        for (const auto word : split_nrrd_words(*units))
            if (word != "\"mm\"" && word != "\"\"")
                throw file_error(path, "space units " + printable(word) + " are not supported (only \"mm\")");
    // LPS from the file's frame: negate x and y for RAS, y for LAS.
    Eigen::Vector3d to_lps(1.0, 1.0, 1.0);
    if (space == Space::ras) to_lps = Eigen::Vector3d(-1.0, -1.0, 1.0);
    if (space == Space::las) to_lps = Eigen::Vector3d(1.0, -1.0, 1.0);

    // Per axis: its world step (with a space), its spacing (without), and whether it is spatial.
    const auto directions = per_axis(path, h, "spacedirections", "space directions", dim);
    const auto spacings = per_axis(path, h, "spacings", "spacings", dim);
    const auto kinds = per_axis(path, h, "kinds", "kinds", dim);
    if (has_space && directions.empty()) throw file_error(path, "header has a space but no 'space directions'");
    std::vector<std::size_t> spatial;
    std::vector<Eigen::Vector3d> steps;
    std::int64_t layers = 1;
    for (std::size_t a = 0; a < dim; ++a) {
        bool is_spatial = kinds.empty() || is_domain_kind(kinds[a]);
        Eigen::Vector3d step = Eigen::Vector3d::Zero();
        if (has_space) {
            if (lower(directions[a]) == "none") {
                is_spatial = false;
            } else {
                step = parse_vector(path, "space directions", directions[a]).cwiseProduct(to_lps);
                if (step.norm() == 0.0)
                    throw file_error(path, "'space directions' vector of axis " + std::to_string(a) +
                                               " has zero length (zero voxel spacing)");
            }
        } else {
            const double s = spacings.empty() ? 1.0 : field_double(path, "spacings", spacings[a], true);
            if (std::isnan(s)) {
                is_spatial = false;
            } else if (!(s > 0.0)) {
                throw file_error(path, "'spacings' of axis " + std::to_string(a) + " is " + printable(spacings[a]) +
                                           " (must be positive)");
            }
            // Axis-aligned: the i-th spatial axis steps along world axis i (more than 3 are refused below).
            if (is_spatial && spatial.size() < 3) step[static_cast<Eigen::Index>(spatial.size())] = s;
        }
        if (is_spatial) {
            spatial.push_back(a);
            steps.push_back(step);
        } else if (layered && a == 0 && sizes[a] > 1) {
            layers = sizes[a]; // a segmentation's layers: the fastest axis, each sample one layer's label
        } else if (sizes[a] > 1) {
            throw file_error(path, "axis " + std::to_string(a) + " (" + std::to_string(sizes[a]) +
                                       " samples) is not spatial: only scalar volumes are supported, not vector, "
                                       "colour or time series data");
        }
    }
    if (spatial.size() != 2 && spatial.size() != 3)
        throw file_error(path, "has " + std::to_string(spatial.size()) +
                                   " spatial axes: only 2-D and 3-D volumes are supported");
    v.dims = {1, 1, 1};
    for (std::size_t i = 0; i < spatial.size(); ++i) v.dims[i] = sizes[spatial[i]];
    v.index_to_world = Eigen::Matrix4d::Identity();
    for (std::size_t i = 0; i < spatial.size(); ++i)
        v.index_to_world.block<3, 1>(0, static_cast<Eigen::Index>(i)) = steps[i];
    if (spatial.size() == 2) {
        const Eigen::Vector3d normal = steps[0].cross(steps[1]);
        if (normal.norm() == 0.0) throw file_error(path, "the two axes' space directions are parallel");
        v.index_to_world.block<3, 1>(0, 2) = normal.normalized();
    }
    if (const std::string* origin = h.find("spaceorigin"))
        v.index_to_world.block<3, 1>(0, 3) = parse_vector(path, "space origin", *origin).cwiseProduct(to_lps);

    // The data: attached after the header, or in a detached file relative to the header's folder.
    DataSource src{path, h.end, path};
    if (const std::string* data_file = h.find("datafile")) {
        const auto words = split_nrrd_words(*data_file);
        if (words.empty()) throw file_error(path, "'data file' is empty");
        if (words[0] == "LIST") throw file_error(path, "data file LIST (one file per slice) is not supported");
        if (words.size() > 1 && words[0].find('%') != std::string_view::npos)
            throw file_error(path, "data file '" + printable(*data_file) +
                                       "' is a numbered pattern (one file per slice), which is not supported");
        const std::filesystem::path name(*data_file);
        src.file = (name.is_absolute() ? name : std::filesystem::path(path).parent_path() / name).string();
        src.offset = 0;
        src.what = path + " (data file " + src.file + ")";
        std::error_code ec;
        if (std::filesystem::is_directory(src.file, ec))
            throw file_error(path, "data file '" + src.file + "' is a folder, not a file");
        if (!std::filesystem::is_regular_file(src.file, ec))
            throw file_error(path, "data file '" + src.file + "' does not exist");
    }
    const std::int64_t line_skip = h.find("lineskip") ? parse_int(path, "line skip", *h.find("lineskip")) : 0;
    const std::int64_t byte_skip = h.find("byteskip") ? parse_int(path, "byte skip", *h.find("byteskip")) : 0;
    if (line_skip < 0) throw file_error(path, "line skip " + std::to_string(line_skip) + " is negative");
    if (byte_skip < -1) throw file_error(path, "byte skip " + std::to_string(byte_skip) + " is below -1");
    if (byte_skip == -1 && encoding != Encoding::raw)
        throw file_error(path, "byte skip -1 (data at the end of the file) is supported with raw encoding only");

    check_allocation(path, count, scalar_size(v.type));
    const std::uint64_t bytes = count * scalar_size(v.type);
    // The data's checks count voxels by v.dims: while it is read, layers count as voxels of axis 0.
    const std::int64_t columns = v.dims[0];
    v.dims[0] *= layers;
    const std::uint64_t size = file_size(src);
    const std::uint64_t start = line_skip > 0 ? skip_lines(src, src.offset, line_skip) : src.offset;
    const std::uint64_t after = size > start ? size - start : 0;

    switch (encoding) {
    case Encoding::raw: {
        const std::uint64_t skip =
            byte_skip == -1 ? (after > bytes ? after - bytes : 0) : static_cast<std::uint64_t>(byte_skip);
        check_voxel_bytes(v, after > skip ? after - skip : 0, src.what);
        v.data = read_range(src, start + skip, bytes);
        break;
    }
    case Encoding::gzip: {
        const auto skip = static_cast<std::uint64_t>(byte_skip);
        const std::vector<std::byte> zipped = read_range(src, start, after);
        v.data = inflate_exact(zipped.data(), zipped.size(), skip + bytes, src.what);
        v.data.erase(v.data.begin(), v.data.begin() + static_cast<std::ptrdiff_t>(skip));
        break;
    }
    case Encoding::ascii: {
        const auto skip = std::min(after, static_cast<std::uint64_t>(byte_skip));
        const std::vector<std::byte> text = read_range(src, start + skip, after - skip);
        v.data.resize(bytes);
        parse_ascii(src.what, std::string_view(reinterpret_cast<const char*>(text.data()), text.size()), v);
        break;
    }
    }
    if (encoding != Encoding::ascii && big_endian != (std::endian::native == std::endian::big)) swap_bytes(v);
    v.dims[0] = columns;
    NrrdImage image;
    image.pairs = h.pairs;
    if (layers == 1) {
        validate(v);
        image.layers.push_back(std::move(v));
        return image;
    }
    // De-interleave the layers (the fastest axis) into one volume each.
    const std::size_t width = scalar_size(v.type);
    const auto voxels = static_cast<std::size_t>(v.voxel_count());
    for (std::int64_t l = 0; l < layers; ++l) {
        Volume layer;
        layer.dims = v.dims;
        layer.index_to_world = v.index_to_world;
        layer.type = v.type;
        layer.scale_slope = v.scale_slope;
        layer.scale_intercept = v.scale_intercept;
        layer.source = v.source;
        layer.data.resize(voxels * width);
        for (std::size_t n = 0; n < voxels; ++n)
            std::memcpy(layer.data.data() + n * width,
                        v.data.data() + (n * static_cast<std::size_t>(layers) + static_cast<std::size_t>(l)) * width, width);
        image.layers.push_back(std::move(layer));
    }
    for (const Volume& layer : image.layers) validate(layer);
    return image;
}

} // namespace vox::io
