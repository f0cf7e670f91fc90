// Wavefront OBJ reader, polygon meshes only (https://paulbourke.net/dataformats/obj/):
//
// - "v x y z [w]" adds a vertex (w, and the r g b some exporters append, are read and ignored);
//   vertices are numbered from 1 in the order they appear.
// - "f c1 c2 c3 ..." adds a polygon, fan-triangulated; a corner is "i", "i/j", "i//k" or "i/j/k"
//   where i is the vertex (texture and normal indices j, k are checked for form and ignored). A
//   negative i counts back from the last vertex defined so far (-1 is the latest).
// - The other records of the format (vt, vn, vp, o, g, s, usemtl, mtllib, l, p, curves and
//   surfaces...) are ignored, as are '#' comments; a line ending in '\' continues on the next. A
//   keyword the format does not have is refused: a misspelt "v" must not drop a vertex and shift
//   every later index.
//
// Parsed here rather than by OpenMesh because OpenMesh's OBJ reader accepts damaged files silently
// (checked with OpenMesh 9.0): a vertex "v nan 10 0" is dropped, which shifts every later index so
// the file imports as another shape without error.

#include "core/error.hpp"
#include "io/file_bytes.hpp"
#include "io/mesh_readers.hpp"
#include "io/text_parsing.hpp"

#include <algorithm>
#include <iterator>
#include <limits>

namespace vox::io::detail {
namespace {

/// One record: its words (comment removed, continuation lines joined) and its first line's number.
class RecordReader {
public:
    explicit RecordReader(std::string_view text) : m_text(text) {}

    bool next(std::vector<std::string_view>& words)
    {
        while (m_pos < m_text.size()) {
            m_line = m_next_line;
            std::string_view record = take_line();
            if (continues(record)) {
                m_joined.clear();
                while (continues(record) && m_pos < m_text.size()) {
                    const std::string_view t = trim(record);
                    m_joined.append(t.substr(0, t.size() - 1));
                    m_joined += ' ';
                    record = take_line();
                }
                m_joined.append(continues(record) ? trim(record).substr(0, trim(record).size() - 1) : record);
                record = m_joined;
            }
            words = split_words(record.substr(0, record.find('#')));
            if (!words.empty()) return true;
        }
        return false;
    }

    /// The number of the line the current record starts on (1-based).
    [[nodiscard]] std::size_t line_number() const { return m_line; }

private:
    std::string_view take_line()
    {
        std::size_t end = m_text.find('\n', m_pos);
        if (end == std::string_view::npos) end = m_text.size();
        const std::string_view line = m_text.substr(m_pos, end - m_pos);
        m_pos = end + 1;
        ++m_next_line;
        return line;
    }

    /// A line whose last character (comments aside) is a backslash continues on the next line.
    static bool continues(std::string_view line)
    {
        const std::string_view t = trim(line);
        return !t.empty() && t.back() == '\\' && t.find('#') == std::string_view::npos;
    }

    std::string_view m_text;
    std::size_t m_pos = 0;
    std::size_t m_line = 0;
    std::size_t m_next_line = 1;
    std::string m_joined;
};

/// The keywords of the format other than "v" and "f" (Wavefront's OBJ specification, version 3.0):
/// texture and normal vertices, lines and points, free-form geometry, grouping, display and
/// rendering attributes.
bool is_ignored_keyword(std::string_view key)
{
    static constexpr std::string_view keywords[] = {
        "vt",     "vn",     "vp",     "l",     "p",         "cstype",   "deg",      "bmat",      "step",
        "curv",   "curv2",  "surf",   "parm",  "trim",      "hole",     "scrv",     "sp",        "end",
        "con",    "g",      "s",      "mg",    "o",         "bevel",    "c_interp", "d_interp",  "lod",
        "usemtl", "mtllib", "maplib", "usemap", "shadow_obj", "trace_obj", "ctech",  "stech",     "call",
        "csh",    "res"};
    return std::find(std::begin(keywords), std::end(keywords), key) != std::end(keywords);
}

/// A face corner's vertex index referred to a later line than its own: checked once every vertex
/// is known.
struct ForwardReference {
    long long index = 0;
    std::size_t line = 0;
};

class ObjParser {
public:
    ObjParser(const std::string& path, std::string_view text) : m_path(path), m_records(text) {}

    TriangleMesh parse()
    {
        std::vector<std::string_view> words;
        std::size_t faces = 0;
        while (m_records.next(words)) {
            if (words[0] == "v") {
                add_vertex(words);
            } else if (words[0] == "f" || words[0] == "fo") { // "fo" is the old keyword for "f"
                add_face(words);
                ++faces;
            } else if (!is_ignored_keyword(words[0])) {
                throw at_line("unknown record '" + printable(words[0]) + "' (not an OBJ keyword)");
            }
        }
        const std::size_t n = m_builder.mesh.vertices.size();
        for (const ForwardReference& ref : m_forward)
            if (static_cast<std::size_t>(ref.index) > n)
                throw file_error(m_path, "line " + std::to_string(ref.line) + ": face references vertex " +
                                             std::to_string(ref.index) + ", but the file has only " +
                                             std::to_string(n) + " vertices");
        if (faces == 0)
            throw file_error(m_path, "has no faces (no 'f' record; " + std::to_string(n) +
                                         " vertices): a surface mesh is needed");
        return m_builder.finish(m_path);
    }

private:
    [[nodiscard]] InputError at_line(const std::string& what) const
    {
        return file_error(m_path, "line " + std::to_string(m_records.line_number()) + ": " + what);
    }

    void add_vertex(const std::vector<std::string_view>& words)
    {
        const std::string number = std::to_string(m_builder.mesh.vertices.size() + 1);
        if (words.size() < 4) throw at_line("vertex " + number + " has fewer than 3 coordinates");
        Eigen::Vector3d p;
        for (std::size_t w = 1; w < words.size(); ++w) {
            const auto x = parse_double(words[w]);
            if (!x) throw at_line("vertex " + number + ": '" + printable(words[w]) + "' is not a number");
            if (w <= 3) p[static_cast<Eigen::Index>(w - 1)] = *x;
        }
        if (!p.allFinite()) throw at_line("vertex " + number + " has a non-finite coordinate " + format_point(p));
        m_builder.mesh.vertices.push_back(p);
    }

    /// The 0-based vertex of corner "i[/j[/k]]". An index beyond the vertices defined so far is
    /// recorded, to be checked against the final count.
    int corner_vertex(std::string_view corner)
    {
        const auto parts = split_corner(corner);
        const auto bad = [&] { return at_line("face corner '" + printable(corner) + "' is not a vertex index "
                                              "(expected i, i/j, i//k or i/j/k)"); };
        if (parts.size() > 3 || parts[0].empty()) throw bad();
        for (std::size_t k = 1; k < parts.size(); ++k)
            if (!parts[k].empty() && !parse_integer(parts[k])) throw bad();
        const auto i = parse_integer(parts[0]);
        if (!i) throw bad();
        const auto n = static_cast<long long>(m_builder.mesh.vertices.size());
        if (*i == 0)
            throw at_line("face references vertex 0; OBJ vertex indices start at 1 (negative ones count back)");
        if (*i < 0) {
            if (-*i > n)
                throw at_line("face references vertex " + std::to_string(*i) + " (counting back), but only " +
                              std::to_string(n) + " vertices are defined before it");
            return static_cast<int>(n + *i);
        }
        if (*i > std::numeric_limits<int>::max())
            throw at_line("face references vertex " + std::to_string(*i) + ", beyond any mesh this program reads");
        if (*i > n) m_forward.push_back({*i, m_records.line_number()});
        return static_cast<int>(*i - 1);
    }

    static std::vector<std::string_view> split_corner(std::string_view corner)
    {
        std::vector<std::string_view> parts;
        std::size_t pos = 0;
        while (true) {
            const auto slash = corner.find('/', pos);
            parts.push_back(corner.substr(pos, slash == std::string_view::npos ? corner.size() - pos : slash - pos));
            if (slash == std::string_view::npos) return parts;
            pos = slash + 1;
        }
    }

    void add_face(const std::vector<std::string_view>& words)
    {
        if (words.size() < 4)
            throw at_line("a face needs at least 3 vertices, this one has " + std::to_string(words.size() - 1));
        if (words.size() - 1 > k_max_face_corners) throw at_line(too_many_corners(double(words.size() - 1)));
        m_corners.clear();
        for (std::size_t w = 1; w < words.size(); ++w) m_corners.push_back(corner_vertex(words[w]));
        m_builder.add_polygon(m_corners);
    }

    const std::string& m_path;
    RecordReader m_records;
    MeshBuilder m_builder;
    std::vector<int> m_corners;
    std::vector<ForwardReference> m_forward;
};

} // namespace

TriangleMesh read_obj(const std::string& path)
{
    const std::vector<std::byte> bytes = read_file_bytes(path);
    std::string_view text(reinterpret_cast<const char*>(bytes.data()), bytes.size());
    if (text.starts_with("\xEF\xBB\xBF")) text.remove_prefix(3); // a UTF-8 byte order mark
    if (is_binary(text.substr(0, 4096)))
        throw file_error(path, "not an OBJ file: it holds binary data, and OBJ is text");
    return ObjParser(path, text).parse();
}

} // namespace vox::io::detail
