// PLY reader (http://paulbourke.net/dataformats/ply/): a text header, then the data of each element
// in header order, as text or binary.
//
// - Header: "ply", "format ascii|binary_little_endian|binary_big_endian 1.0", then "element NAME
//   COUNT" lines, each followed by its "property TYPE NAME" and "property list COUNT_TYPE
//   ITEM_TYPE NAME" lines, up to "end_header"; "comment" and "obj_info" lines are ignored. Types:
//   char uchar short ushort int uint float double, or int8 uint8 int16 uint16 int32 uint32
//   float32 float64.
// - Element "vertex" gives the points by its properties x, y and z (any scalar type; the others,
//   normals and colours, are skipped). Element "face" gives the polygons by its list property
//   vertex_indices (or vertex_index), 0-based; polygons are fan-triangulated. Other elements
//   (edges, materials...) are read past, before or after, ascii or binary.
// - Ascii data has one element instance per line.
//
// Parsed here rather than by OpenMesh because OpenMesh's PLY reader accepts damaged files silently
// (checked with OpenMesh 9.0): a face with an out-of-range vertex index is dropped, and the file
// loads with a face fewer and no error.

#include "core/error.hpp"
#include "core/memory_limit.hpp"
#include "io/file_bytes.hpp"
#include "io/mesh_readers.hpp"
#include "io/text_parsing.hpp"

#include <algorithm>
#include <array>
#include <bit>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <optional>
#include <type_traits>

namespace vox::io::detail {
namespace {

enum class PlyType { i8, u8, i16, u16, i32, u32, f32, f64 };
enum class PlyFormat { ascii, binary_little_endian, binary_big_endian };

struct TypeInfo {
    PlyType type;
    std::size_t size;
    double min; ///< the range of an integer type (for ascii values); unused for floats
    double max;
};

std::optional<TypeInfo> parse_type(std::string_view name)
{
    struct Named {
        std::string_view a, b;
        TypeInfo info;
    };
    static constexpr std::array<Named, 8> types = {{
        {"char", "int8", {PlyType::i8, 1, -128.0, 127.0}},
        {"uchar", "uint8", {PlyType::u8, 1, 0.0, 255.0}},
        {"short", "int16", {PlyType::i16, 2, -32768.0, 32767.0}},
        {"ushort", "uint16", {PlyType::u16, 2, 0.0, 65535.0}},
        {"int", "int32", {PlyType::i32, 4, -2147483648.0, 2147483647.0}},
        {"uint", "uint32", {PlyType::u32, 4, 0.0, 4294967295.0}},
        {"float", "float32", {PlyType::f32, 4, 0.0, 0.0}},
        {"double", "float64", {PlyType::f64, 8, 0.0, 0.0}},
    }};
    for (const Named& t : types)
        if (name == t.a || name == t.b) return t.info;
    return std::nullopt;
}

bool is_integer(PlyType t) { return t != PlyType::f32 && t != PlyType::f64; }

struct Property {
    std::string name;
    TypeInfo type{};       ///< of the value, or of a list's items
    bool is_list = false;
    TypeInfo count_type{}; ///< of a list's length
};

struct Element {
    std::string name;
    long long count = 0;
    std::vector<Property> properties;
};

struct Header {
    PlyFormat format = PlyFormat::ascii;
    std::vector<Element> elements;
    std::size_t data_start = 0; ///< byte offset just past the "end_header" line
    std::size_t data_line = 0;  ///< line number of the first data line (ascii)
};

std::string quoted(std::string_view s) { return "'" + printable(s) + "'"; }

Header parse_header(const std::string& path, std::string_view text)
{
    if (!text.starts_with("ply\n") && !text.starts_with("ply\r\n"))
        throw file_error(path, "not a PLY file (it does not start with the line 'ply')");
    Header h;
    bool has_format = false;
    std::size_t pos = 0;
    for (std::size_t line_no = 1;; ++line_no) {
        if (pos >= text.size()) throw file_error(path, "truncated: the header has no 'end_header' line");
        std::size_t end = text.find('\n', pos);
        if (end == std::string_view::npos) end = text.size();
        const std::string_view line = text.substr(pos, end - pos);
        pos = end + 1;
        if (line_no == 1) continue; // "ply"
        const auto at_line = [&](const std::string& what) {
            return file_error(path, "header line " + std::to_string(line_no) + ": " + what);
        };
        if (is_binary(line)) throw at_line("holds binary data; the header is text up to 'end_header'");
        const std::vector<std::string_view> words = split_words(line);
        if (words.empty()) continue;
        const std::string_view key = words[0];
        if (key == "comment" || key == "obj_info") continue;
        if (key == "end_header") {
            if (!has_format) throw file_error(path, "the header has no 'format' line");
            h.data_start = std::min(pos, text.size());
            h.data_line = line_no + 1;
            return h;
        }
        if (key == "format") {
            if (has_format) throw at_line("a second 'format' line");
            if (words.size() != 3) throw at_line("expected 'format ascii|binary_little_endian|binary_big_endian 1.0'");
            if (words[1] == "ascii") h.format = PlyFormat::ascii;
            else if (words[1] == "binary_little_endian") h.format = PlyFormat::binary_little_endian;
            else if (words[1] == "binary_big_endian") h.format = PlyFormat::binary_big_endian;
            else throw at_line("unsupported format " + quoted(words[1]) +
                               " (expected ascii, binary_little_endian or binary_big_endian)");
            if (words[2] != "1.0") throw at_line("unsupported PLY version " + quoted(words[2]) + " (expected 1.0)");
            has_format = true;
        } else if (key == "element") {
            const auto count = words.size() == 3 ? parse_integer(words[2]) : std::nullopt;
            if (!count || *count < 0) throw at_line("expected 'element NAME COUNT' with a non-negative count");
            for (const Element& e : h.elements)
                if (e.name == words[1]) throw at_line("element " + quoted(words[1]) + " is declared twice");
            h.elements.push_back({std::string(words[1]), *count, {}});
        } else if (key == "property") {
            if (h.elements.empty()) throw at_line("a property before any 'element' line");
            Property p;
            const bool list = words.size() >= 2 && words[1] == "list";
            if (words.size() != (list ? 5u : 3u))
                throw at_line("expected 'property TYPE NAME' or 'property list COUNT_TYPE ITEM_TYPE NAME'");
            const std::string_view type_word = words[list ? 3 : 1];
            const auto type = parse_type(type_word);
            if (!type) throw at_line("unknown property type " + quoted(type_word));
            p.type = *type;
            p.name = words.back();
            if (list) {
                const auto count_type = parse_type(words[2]);
                if (!count_type || !is_integer(count_type->type))
                    throw at_line("list count type " + quoted(words[2]) + " is not an integer type");
                p.is_list = true;
                p.count_type = *count_type;
            }
            h.elements.back().properties.push_back(p);
        } else {
            throw at_line("unknown header keyword " + quoted(key));
        }
    }
}

/// Where the vertex coordinates and the face lists are in the elements' properties.
struct Layout {
    const Element* vertex = nullptr;
    const Element* face = nullptr;
    std::array<std::size_t, 3> xyz{};  ///< property indices of x, y, z in `vertex`
    std::size_t indices = 0;           ///< property index of the vertex index list in `face`
};

Layout find_layout(const std::string& path, const Header& h)
{
    Layout l;
    for (const Element& e : h.elements) {
        if (e.name == "vertex") l.vertex = &e;
        if (e.name == "face") l.face = &e;
    }
    if (!l.vertex) throw file_error(path, "the header has no 'element vertex'");
    for (int c = 0; c < 3; ++c) {
        const std::string name(1, "xyz"[c]);
        const auto& props = l.vertex->properties;
        const auto it = std::find_if(props.begin(), props.end(), [&](const Property& p) { return p.name == name; });
        if (it == props.end()) throw file_error(path, "element vertex has no property '" + name + "'");
        if (it->is_list) throw file_error(path, "vertex property '" + name + "' is a list, not a number");
        l.xyz[static_cast<std::size_t>(c)] = static_cast<std::size_t>(it - props.begin());
    }
    if (!l.face || l.face->count == 0)
        throw file_error(path, "has no faces (" + std::string(l.face ? "'element face 0'" : "no 'element face'") +
                                   "; " + std::to_string(l.vertex->count) + " vertices): a surface mesh is needed");
    const auto& props = l.face->properties;
    const auto it = std::find_if(props.begin(), props.end(), [](const Property& p) {
        return p.name == "vertex_indices" || p.name == "vertex_index";
    });
    if (it == props.end()) throw file_error(path, "element face has no list property 'vertex_indices'");
    if (!it->is_list || !is_integer(it->type.type))
        throw file_error(path, "face property '" + it->name + "' must be a list of integers");
    l.indices = static_cast<std::size_t>(it - props.begin());
    return l;
}

/// Binary data: values of the declared types, in the file's byte order.
class BinarySource {
public:
    BinarySource(std::string_view data, bool big_endian)
        : m_data(data), m_swap(big_endian != (std::endian::native == std::endian::big))
    {
    }

    [[nodiscard]] bool begin_instance() { return true; }
    void end_instance() {}
    [[nodiscard]] std::string where() const { return {}; }

    /// The next value; nullopt at the end of the data.
    std::optional<double> value(const TypeInfo& t)
    {
        if (m_data.size() - m_pos < t.size) return std::nullopt;
        std::array<unsigned char, 8> b{};
        const std::size_t size = std::min(t.size, b.size()); // PLY scalars have at most 8 bytes
        std::memcpy(b.data(), m_data.data() + m_pos, size);
        if (m_swap) std::reverse(b.begin(), b.begin() + static_cast<std::ptrdiff_t>(size));
        m_pos += t.size;
        switch (t.type) {
        case PlyType::i8: return as<std::int8_t>(b);
        case PlyType::u8: return as<std::uint8_t>(b);
        case PlyType::i16: return as<std::int16_t>(b);
        case PlyType::u16: return as<std::uint16_t>(b);
        case PlyType::i32: return as<std::int32_t>(b);
        case PlyType::u32: return as<std::uint32_t>(b);
        case PlyType::f32: return as<float>(b);
        case PlyType::f64: return as<double>(b);
        }
        return std::nullopt;
    }

    /// Describes data after the last element, or returns "" when there is none (a trailing line
    /// break some writers add is allowed).
    [[nodiscard]] std::string trailing_data() const
    {
        const std::string_view rest = m_data.substr(m_pos);
        if (rest.find_first_not_of("\r\n") == std::string_view::npos) return {};
        return "holds " + std::to_string(rest.size()) + " bytes after the last element the header declares";
    }

private:
    template <class T> static double as(const std::array<unsigned char, 8>& b)
    {
        T v;
        std::memcpy(&v, b.data(), sizeof(T));
        return static_cast<double>(v);
    }

    std::string_view m_data;
    bool m_swap;
    std::size_t m_pos = 0;
};

/// Ascii data: one element instance per line, values separated by blanks.
class AsciiSource {
public:
    AsciiSource(const std::string& path, std::string_view data, std::size_t first_line)
        : m_path(path), m_data(data), m_next_line(first_line)
    {
    }

    /// Moves to the next non-blank line; false at the end of the data.
    [[nodiscard]] bool begin_instance()
    {
        while (m_pos < m_data.size()) {
            std::size_t end = m_data.find('\n', m_pos);
            if (end == std::string_view::npos) end = m_data.size();
            m_words = split_words(m_data.substr(m_pos, end - m_pos));
            m_pos = end + 1;
            m_line = m_next_line++;
            m_word = 0;
            if (!m_words.empty()) return true;
        }
        return false;
    }

    /// Refuses values left on the line.
    void end_instance() const
    {
        if (m_word < m_words.size())
            throw file_error(m_path, where() + "more values than the element's properties declare (" +
                                         quoted(m_words[m_word]) + " is one too many)");
    }

    [[nodiscard]] std::string where() const { return "line " + std::to_string(m_line) + ": "; }

    /// The next value on the line, checked against its type; nullopt when the line has no more.
    std::optional<double> value(const TypeInfo& t)
    {
        if (m_word == m_words.size()) return std::nullopt;
        const std::string_view word = m_words[m_word++];
        if (is_integer(t.type)) {
            const auto v = parse_integer(word);
            if (!v) throw file_error(m_path, where() + quoted(word) + " is not an integer");
            if (static_cast<double>(*v) < t.min || static_cast<double>(*v) > t.max)
                throw file_error(m_path, where() + quoted(word) + " does not fit its property's type");
            return static_cast<double>(*v);
        }
        const auto v = parse_double(word);
        if (!v) throw file_error(m_path, where() + quoted(word) + " is not a number");
        return *v;
    }

    [[nodiscard]] std::string trailing_data()
    {
        if (!begin_instance()) return {};
        return where() + "data after the last element the header declares";
    }

private:
    const std::string& m_path;
    std::string_view m_data;
    std::size_t m_pos = 0;
    std::size_t m_next_line;
    std::size_t m_line = 0;
    std::vector<std::string_view> m_words;
    std::size_t m_word = 0;
};

/// Reads every element's data from `src` in header order, keeping the vertices and faces.
template <class Source>
TriangleMesh read_elements(const std::string& path, const Header& h, const Layout& layout, Source& src,
                           std::size_t data_bytes)
{
    const long long vertex_count = layout.vertex->count;
    check_allocation(path, static_cast<std::uint64_t>(vertex_count), sizeof(Eigen::Vector3d));
    check_allocation(path, static_cast<std::uint64_t>(layout.face->count), sizeof(Eigen::Vector3i));
    MeshBuilder builder;
    // The header may lie; a vertex takes at least 3 bytes of data, so the data bounds the count.
    builder.mesh.vertices.reserve(static_cast<std::size_t>(std::min<long long>(vertex_count, data_bytes / 3)));
    std::vector<int> corners;

    for (const Element& e : h.elements) {
        if (e.properties.empty()) continue; // nothing stored per instance
        const bool is_vertex = &e == layout.vertex;
        const bool is_face = &e == layout.face;
        for (long long k = 0; k < e.count; ++k) {
            const auto truncated = [&] {
                return file_error(path, "truncated: the data ends in " + e.name + " " + std::to_string(k) + " of the " +
                                            std::to_string(e.count) + " the header declares");
            };
            if (!src.begin_instance()) throw truncated();
            // A value missing within an instance: the end of the data (binary) or of the line (ascii).
            const auto missing = [&] {
                if constexpr (std::is_same_v<Source, AsciiSource>)
                    return file_error(path, src.where() + e.name + " " + std::to_string(k) +
                                                " has fewer values than its properties declare");
                else
                    return truncated();
            };
            Eigen::Vector3d p = Eigen::Vector3d::Zero();
            for (std::size_t i = 0; i < e.properties.size(); ++i) {
                const Property& prop = e.properties[i];
                if (!prop.is_list) {
                    const auto v = src.value(prop.type);
                    if (!v) throw missing();
                    if (is_vertex)
                        for (int c = 0; c < 3; ++c)
                            if (layout.xyz[static_cast<std::size_t>(c)] == i) p[c] = *v;
                    continue;
                }
                const auto n = src.value(prop.count_type);
                if (!n) throw missing();
                if (*n < 0)
                    throw file_error(path, src.where() + e.name + " " + std::to_string(k) + ": list '" + prop.name +
                                               "' has a negative length");
                const bool keep = is_face && i == layout.indices;
                if (keep) {
                    if (*n < 3)
                        throw file_error(path, src.where() + "face " + std::to_string(k) + " has " +
                                                   number_text(*n) + " vertices; a face needs at least 3");
                    if (*n > static_cast<double>(k_max_face_corners))
                        throw file_error(path, src.where() + "face " + std::to_string(k) + ": " + too_many_corners(*n));
                    corners.clear();
                }
                for (double m = 0; m < *n; ++m) {
                    const auto v = src.value(prop.type);
                    if (!v) throw missing();
                    if (!keep) continue;
                    if (*v < 0 || *v >= static_cast<double>(vertex_count))
                        throw file_error(path, src.where() + "face " + std::to_string(k) + " references vertex " +
                                                   number_text(*v) + ", but there are only " +
                                                   std::to_string(vertex_count) + " vertices");
                    corners.push_back(static_cast<int>(*v));
                }
                if (keep) builder.add_polygon(corners);
            }
            src.end_instance();
            if (is_vertex) {
                if (!p.allFinite())
                    throw file_error(path, src.where() + "vertex " + std::to_string(k) +
                                               " has a non-finite coordinate " + format_point(p));
                builder.mesh.vertices.push_back(p);
            }
        }
    }
    if (const std::string extra = src.trailing_data(); !extra.empty()) throw file_error(path, extra);
    return builder.finish(path);
}

} // namespace

TriangleMesh read_ply(const std::string& path)
{
    const std::vector<std::byte> bytes = read_file_bytes(path);
    const std::string_view text(reinterpret_cast<const char*>(bytes.data()), bytes.size());
    const Header h = parse_header(path, text);
    const Layout layout = find_layout(path, h);
    const std::string_view data = text.substr(h.data_start);
    if (h.format == PlyFormat::ascii) {
        AsciiSource src(path, data, h.data_line);
        return read_elements(path, h, layout, src, data.size());
    }
    BinarySource src(data, h.format == PlyFormat::binary_big_endian);
    return read_elements(path, h, layout, src, data.size());
}

} // namespace vox::io::detail
