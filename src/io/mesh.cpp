// Surface mesh reading and summary.
//
// OFF and STL are parsed here rather than by OpenMesh because OpenMesh's readers accept damaged
// files silently (checked with OpenMesh 9.0): an OFF vertex "nan" breaks its stream parse and every
// face is then dropped, a truncated OFF gets made-up vertices, a NaN in a binary STL is merged into
// another vertex, and a truncated binary STL reads as an empty mesh without error. Both formats are
// simple enough to check byte for byte. OBJ and PLY, with their many variants, go through OpenMesh.

#include "io/mesh.hpp"

#include "core/error.hpp"
#include "core/log.hpp"
#include "core/memory_limit.hpp"
#include "io/file_bytes.hpp"

#include <Eigen/Geometry>
#include <OpenMesh/Core/IO/MeshIO.hh>
#include <OpenMesh/Core/Mesh/PolyMesh_ArrayKernelT.hh>

#include <algorithm>
#include <array>
#include <bit>
#include <cctype>
#include <charconv>
#include <cmath>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <map>
#include <mutex>
#include <numeric>
#include <optional>
#include <sstream>
#include <string_view>
#include <unordered_map>

namespace vox::io {
namespace {

// ---------------------------------------------------------------------------------------------
// Building a mesh from polygons

/// Accumulates polygons as triangle fans, skipping triangles that repeat a vertex (zero area).
struct MeshBuilder {
    TriangleMesh mesh;
    std::size_t skipped_faces = 0;

    void add_polygon(const std::vector<int>& corners)
    {
        bool kept = false;
        for (std::size_t i = 1; i + 1 < corners.size(); ++i) {
            const Eigen::Vector3i t(corners[0], corners[i], corners[i + 1]);
            if (t[0] == t[1] || t[1] == t[2] || t[0] == t[2]) continue;
            mesh.triangles.push_back(t);
            kept = true;
        }
        if (!kept) ++skipped_faces;
    }

    TriangleMesh finish(const std::string& path)
    {
        if (skipped_faces > 0)
            log::warn("{}: skipped {} face(s) that repeat a vertex (zero area)", path, skipped_faces);
        return std::move(mesh);
    }
};

/// Gives one index per distinct position, so triangles listed with their own corners (STL) share
/// vertices. Positions must be finite.
class VertexWelder {
public:
    explicit VertexWelder(std::vector<Eigen::Vector3d>& vertices) : m_vertices(vertices) {}

    int index_of(const Eigen::Vector3d& p)
    {
        const Eigen::Vector3d q = (p.array() + 0.0).matrix(); // -0.0 + 0.0 == +0.0: one key for both zeros
        const auto [it, inserted] = m_index.try_emplace(Key{q.x(), q.y(), q.z()}, static_cast<int>(m_vertices.size()));
        if (inserted) m_vertices.push_back(q);
        return it->second;
    }

private:
    using Key = std::array<double, 3>;
    struct KeyHash {
        std::size_t operator()(const Key& k) const
        {
            std::uint64_t h = 0;
            for (const double d : k) h = (h ^ std::bit_cast<std::uint64_t>(d)) * 0x100000001b3ull;
            return static_cast<std::size_t>(h ^ (h >> 29));
        }
    };
    std::vector<Eigen::Vector3d>& m_vertices;
    std::unordered_map<Key, int, KeyHash> m_index;
};

// ---------------------------------------------------------------------------------------------
// Text parsing

std::optional<double> parse_double(std::string_view s)
{
    if (!s.empty() && s.front() == '+') s.remove_prefix(1); // from_chars rejects a leading '+'
    double v = 0.0;
    const auto [end, ec] = std::from_chars(s.data(), s.data() + s.size(), v);
    if (ec != std::errc() || end != s.data() + s.size() || s.empty()) return std::nullopt;
    return v;
}

std::optional<long long> parse_integer(std::string_view s)
{
    long long v = 0;
    const auto [end, ec] = std::from_chars(s.data(), s.data() + s.size(), v);
    if (ec != std::errc() || end != s.data() + s.size() || s.empty()) return std::nullopt;
    return v;
}

bool is_space(char c) { return c == ' ' || c == '\t' || c == '\r' || c == '\n' || c == '\v' || c == '\f'; }

std::vector<std::string_view> split_words(std::string_view s)
{
    std::vector<std::string_view> words;
    std::size_t i = 0;
    while (i < s.size()) {
        while (i < s.size() && is_space(s[i])) ++i;
        const std::size_t start = i;
        while (i < s.size() && !is_space(s[i])) ++i;
        if (i > start) words.push_back(s.substr(start, i - start));
    }
    return words;
}

/// Yields the words of each non-blank line, with '#' comments removed, and the line's number.
class LineReader {
public:
    explicit LineReader(std::string_view text) : m_text(text) {}

    bool next(std::vector<std::string_view>& words)
    {
        while (m_pos < m_text.size()) {
            std::size_t end = m_text.find('\n', m_pos);
            if (end == std::string_view::npos) end = m_text.size();
            std::string_view line = m_text.substr(m_pos, end - m_pos);
            m_pos = end + 1;
            ++m_line;
            line = line.substr(0, line.find('#'));
            words = split_words(line);
            if (!words.empty()) return true;
        }
        return false;
    }

    [[nodiscard]] std::size_t line_number() const { return m_line; }

private:
    std::string_view m_text;
    std::size_t m_pos = 0;
    std::size_t m_line = 0;
};

std::string quoted(std::string_view s) { return "'" + std::string(s.substr(0, 40)) + "'"; }

std::string format_point(const Eigen::Vector3d& p)
{
    std::ostringstream s;
    s << '(' << p.x() << ", " << p.y() << ", " << p.z() << ')';
    return s.str();
}

// ---------------------------------------------------------------------------------------------
// OFF: "OFF", then "#vertices #faces #edges", then one vertex "x y z" per line, then one face
// "n i_1 ... i_n" per line (0-based indices). Variants COFF, NOFF, STOFF... add per-line fields
// after the ones we read. https://segeval.cs.princeton.edu/public/off_format.html

struct OffCounts {
    long long vertices = 0;
    long long faces = 0;
};

OffCounts parse_off_header(const std::string& path, LineReader& lines)
{
    std::vector<std::string_view> words;
    if (!lines.next(words) || !words[0].ends_with("OFF"))
        throw file_error(path, "not an OFF file (it does not start with the keyword OFF)");
    if (words[0].find('4') != std::string_view::npos || words[0].starts_with('n'))
        throw file_error(path, "only 3-dimensional OFF is supported, not " + std::string(words[0]));
    if (words.size() > 1 && words[1] == "BINARY") throw file_error(path, "binary OFF is not supported");
    words.erase(words.begin());
    if (words.empty() && !lines.next(words)) throw file_error(path, "truncated: no vertex and face counts");
    const auto nv = words.size() >= 2 ? parse_integer(words[0]) : std::nullopt;
    const auto nf = words.size() >= 2 ? parse_integer(words[1]) : std::nullopt;
    if (!nv || !nf || *nv < 0 || *nf < 0)
        throw file_error(path, "line " + std::to_string(lines.line_number()) +
                                   ": expected the vertex and face counts (two non-negative integers)");
    check_allocation(path, static_cast<std::uint64_t>(*nv), sizeof(Eigen::Vector3d));
    check_allocation(path, static_cast<std::uint64_t>(*nf), sizeof(Eigen::Vector3i));
    return {*nv, *nf};
}

TriangleMesh parse_off(const std::string& path, std::string_view text)
{
    LineReader lines(text);
    const OffCounts counts = parse_off_header(path, lines);
    const auto at_line = [&](const std::string& what) {
        return file_error(path, "line " + std::to_string(lines.line_number()) + ": " + what);
    };
    const auto truncated = [&](const std::string& what, long long found) {
        return file_error(path, "truncated: the header declares " + std::to_string(counts.vertices) + " vertices and " +
                                    std::to_string(counts.faces) + " faces, but the file ends after " +
                                    std::to_string(found) + " " + what);
    };

    MeshBuilder builder;
    // The header may lie; a vertex line has at least 6 characters, so the text bounds the count.
    builder.mesh.vertices.reserve(static_cast<std::size_t>(std::min<long long>(counts.vertices, text.size() / 6)));
    std::vector<std::string_view> words;
    for (long long v = 0; v < counts.vertices; ++v) {
        if (!lines.next(words)) throw truncated("vertices", v);
        if (words.size() < 3) throw at_line("vertex " + std::to_string(v) + " has fewer than 3 coordinates");
        Eigen::Vector3d p;
        for (int c = 0; c < 3; ++c) {
            const auto x = parse_double(words[c]);
            if (!x) throw at_line("vertex " + std::to_string(v) + ": " + quoted(words[c]) + " is not a number");
            p[c] = *x;
        }
        builder.mesh.vertices.push_back(p);
    }

    std::vector<int> corners;
    for (long long f = 0; f < counts.faces; ++f) {
        if (!lines.next(words)) throw truncated("faces", f);
        const auto n = parse_integer(words[0]);
        if (!n || *n < 3 || static_cast<std::size_t>(*n) >= words.size())
            throw at_line("face " + std::to_string(f) +
                          ": expected a corner count of at least 3 and that many indices");
        corners.clear();
        for (long long c = 1; c <= *n; ++c) {
            const auto i = parse_integer(words[static_cast<std::size_t>(c)]);
            if (!i || *i < 0 || *i >= counts.vertices)
                throw at_line("face " + std::to_string(f) + " references vertex " + std::string(words[c]) +
                              ", but there are only " + std::to_string(counts.vertices) + " vertices");
            corners.push_back(static_cast<int>(*i));
        }
        builder.add_polygon(corners);
    }
    return builder.finish(path);
}

// ---------------------------------------------------------------------------------------------
// STL: binary is an 80-byte header, a uint32 triangle count, then 50 bytes per triangle (normal,
// three corners as float32 little-endian, a uint16 attribute). Ascii is "solid name", facets
// "facet normal nx ny nz / outer loop / vertex x y z (x3) / endloop / endfacet", "endsolid".

constexpr std::size_t k_stl_header = 84;
constexpr std::size_t k_stl_triangle = 50;

float read_float_le(const std::byte* p)
{
    std::uint32_t bits = 0;
    for (int b = 3; b >= 0; --b) bits = (bits << 8) | std::to_integer<std::uint32_t>(p[b]);
    return std::bit_cast<float>(bits);
}

std::uint32_t binary_stl_count(const std::vector<std::byte>& bytes)
{
    std::uint32_t n = 0;
    for (int b = 3; b >= 0; --b) n = (n << 8) | std::to_integer<std::uint32_t>(bytes[80 + static_cast<std::size_t>(b)]);
    return n;
}

void check_finite_corner(const std::string& path, const Eigen::Vector3d& p, std::size_t triangle, int corner)
{
    if (!p.allFinite())
        throw file_error(path, "triangle " + std::to_string(triangle) + ", corner " + std::to_string(corner) +
                                   " has a non-finite coordinate " + format_point(p));
}

TriangleMesh parse_binary_stl(const std::string& path, const std::vector<std::byte>& bytes)
{
    const std::size_t n = binary_stl_count(bytes);
    MeshBuilder builder;
    VertexWelder welder(builder.mesh.vertices);
    std::vector<int> corners(3);
    for (std::size_t t = 0; t < n; ++t) {
        const std::byte* rec = bytes.data() + k_stl_header + t * k_stl_triangle + 12; // skip the normal
        for (int c = 0; c < 3; ++c) {
            const Eigen::Vector3d p(read_float_le(rec + 12 * c), read_float_le(rec + 12 * c + 4),
                                    read_float_le(rec + 12 * c + 8));
            check_finite_corner(path, p, t, c);
            corners[static_cast<std::size_t>(c)] = welder.index_of(p);
        }
        builder.add_polygon(corners);
    }
    return builder.finish(path);
}

TriangleMesh parse_ascii_stl(const std::string& path, std::string_view text)
{
    const std::vector<std::string_view> words = split_words(text);
    MeshBuilder builder;
    VertexWelder welder(builder.mesh.vertices);
    std::vector<int> corners;
    std::size_t facet = 0;
    bool in_loop = false;
    bool ended = false; // some exporters write several solids into one file
    for (std::size_t w = 0; w < words.size(); ++w) {
        if (words[w] == "solid") {
            ended = false;
        } else if (words[w] == "loop") {
            in_loop = true;
            corners.clear();
        } else if (words[w] == "vertex") {
            if (!in_loop) throw file_error(path, "facet " + std::to_string(facet) + ": 'vertex' outside 'outer loop'");
            Eigen::Vector3d p;
            for (int c = 0; c < 3; ++c) {
                const auto x = w + 1 < words.size() ? parse_double(words[++w]) : std::nullopt;
                if (!x) throw file_error(path, "facet " + std::to_string(facet) + ": a vertex needs 3 numbers");
                p[c] = *x;
            }
            check_finite_corner(path, p, facet, static_cast<int>(corners.size()));
            corners.push_back(welder.index_of(p));
        } else if (words[w] == "endloop") {
            if (corners.size() < 3)
                throw file_error(path, "facet " + std::to_string(facet) + " has " + std::to_string(corners.size()) +
                                           " vertices; a facet needs at least 3");
            builder.add_polygon(corners);
            in_loop = false;
            ++facet;
        } else if (words[w] == "endsolid") {
            ended = true;
        }
    }
    if (in_loop) throw file_error(path, "truncated: facet " + std::to_string(facet) + " has no 'endloop'");
    if (!ended) throw file_error(path, "truncated: no 'endsolid' after " + std::to_string(facet) + " facets");
    return builder.finish(path);
}

TriangleMesh parse_stl(const std::string& path, const std::vector<std::byte>& bytes)
{
    // Binary files may start with "solid" too, so the size test decides first.
    if (bytes.size() >= k_stl_header) {
        const std::uint64_t n = binary_stl_count(bytes);
        if (k_stl_header + k_stl_triangle * n == bytes.size()) return parse_binary_stl(path, bytes);
    }
    const std::string_view text(reinterpret_cast<const char*>(bytes.data()), bytes.size());
    const auto words = split_words(text.substr(0, 64));
    if (!words.empty() && words[0] == "solid") return parse_ascii_stl(path, text);
    if (bytes.size() < k_stl_header)
        throw file_error(path, "not an STL file: " + std::to_string(bytes.size()) +
                                   " bytes, too short for binary STL, and no ascii 'solid' keyword");
    const std::uint64_t n = binary_stl_count(bytes);
    throw file_error(path, "truncated or corrupt binary STL: it declares " + std::to_string(n) + " triangles (" +
                               std::to_string(k_stl_header + k_stl_triangle * n) + " bytes) but has " +
                               std::to_string(bytes.size()) + " bytes");
}

// ---------------------------------------------------------------------------------------------
// OBJ and PLY through OpenMesh

struct OpenMeshTraits : OpenMesh::DefaultTraits {
    using Point = OpenMesh::Vec3d;
};
using PolyMesh = OpenMesh::PolyMesh_ArrayKernelT<OpenMeshTraits>;

/// OpenMesh reports problems on its global streams omerr, omlog and omout, by default the
/// console. While alive, this collects omerr in a string (to fold it into one error message) and
/// keeps the console quiet. The streams are global, so readers holding it are serialised.
class OpenMeshMessages {
public:
    OpenMeshMessages() : m_lock(mutex())
    {
        static std::once_flag once;
        std::call_once(once, [] {
            for (OpenMesh::mostream* s : {&omerr(), &omlog(), &omout()}) {
                s->disconnect(std::cerr);
                s->disconnect(std::clog);
                s->disconnect(std::cout);
            }
            omlog().disable();
            omout().disable();
        });
        omerr().connect(m_text);
    }
    ~OpenMeshMessages() { omerr().disconnect(m_text); }
    OpenMeshMessages(const OpenMeshMessages&) = delete;
    OpenMeshMessages& operator=(const OpenMeshMessages&) = delete;

    [[nodiscard]] std::string text()
    {
        omerr().flush();
        return m_text.str();
    }

private:
    static std::mutex& mutex()
    {
        static std::mutex m;
        return m;
    }
    std::unique_lock<std::mutex> m_lock;
    std::ostringstream m_text;
};

std::size_t count_occurrences(const std::string& text, std::string_view what)
{
    std::size_t n = 0;
    for (std::size_t pos = text.find(what); pos != std::string::npos; pos = text.find(what, pos + what.size())) ++n;
    return n;
}

std::string first_line(const std::string& text)
{
    const std::string line = text.substr(0, text.find('\n'));
    return line.empty() ? std::string() : " (OpenMesh: " + line + ")";
}

/// OpenMesh gives each face it cannot attach manifoldly (a complex edge or vertex, e.g. a flipped
/// triangle or a fourth triangle on an edge) fresh copies of its vertices, flagged
/// fixed_nonmanifold. Maps every OpenMesh vertex to an index in `vertices`, copies to the original
/// at the same position, so the connectivity is the file's.
std::vector<int> weld_nonmanifold_copies(const PolyMesh& pm, std::vector<Eigen::Vector3d>& vertices)
{
    std::map<std::array<double, 3>, int> originals;
    std::vector<int> index(pm.n_vertices(), -1);
    std::size_t copies = 0;
    for (const auto v : pm.vertices()) {
        if (pm.status(v).fixed_nonmanifold()) continue;
        const auto& p = pm.point(v);
        index[static_cast<std::size_t>(v.idx())] = static_cast<int>(vertices.size());
        originals.try_emplace({p[0], p[1], p[2]}, static_cast<int>(vertices.size()));
        vertices.emplace_back(p[0], p[1], p[2]);
    }
    for (const auto v : pm.vertices()) {
        if (!pm.status(v).fixed_nonmanifold()) continue;
        const auto& p = pm.point(v);
        const auto it = originals.find({p[0], p[1], p[2]});
        if (it != originals.end()) {
            index[static_cast<std::size_t>(v.idx())] = it->second;
            ++copies;
        } else {
            index[static_cast<std::size_t>(v.idx())] = static_cast<int>(vertices.size());
            vertices.emplace_back(p[0], p[1], p[2]);
        }
    }
    if (copies > 0) log::debug("welded {} vertex copies OpenMesh made at non-manifold faces", copies);
    return index;
}

TriangleMesh read_with_openmesh(const std::string& path, const std::string& format)
{
    PolyMesh pm;
    pm.request_vertex_status(); // lets OpenMesh flag the vertex copies it makes at non-manifold faces
    OpenMesh::IO::Options options;
    bool ok = false;
    std::string messages;
    {
        OpenMeshMessages capture;
        ok = OpenMesh::IO::read_mesh(pm, path, options);
        messages = capture.text();
    }
    if (!ok) throw file_error(path, "OpenMesh cannot read it as " + format + first_line(messages));
    if (const std::size_t bad = count_occurrences(messages, "invalid vertex index"))
        throw file_error(path, std::to_string(bad) +
                                   " face(s) reference a vertex that does not exist (or a vertex line was unreadable, "
                                   "e.g. 'nan', which shifts the indices)");

    MeshBuilder builder;
    builder.skipped_faces = count_occurrences(messages, "equal vertices"); // OpenMesh dropped these already
    const std::vector<int> index = weld_nonmanifold_copies(pm, builder.mesh.vertices);
    std::vector<int> corners;
    for (const auto f : pm.faces()) {
        corners.clear();
        for (const auto v : pm.fv_range(f)) corners.push_back(index[static_cast<std::size_t>(v.idx())]);
        builder.add_polygon(corners);
    }
    return builder.finish(path);
}

// ---------------------------------------------------------------------------------------------

void check_file_readable(const std::string& path)
{
    std::error_code ec;
    const auto status = std::filesystem::status(path, ec);
    if (ec || !std::filesystem::exists(status)) throw file_error(path, "no such file");
    if (std::filesystem::is_directory(status)) throw file_error(path, "is a folder, not a file");
    if (!std::ifstream(path, std::ios::binary)) throw file_error(path, "cannot open: permission denied or unreadable");
}

std::string lower_extension(const std::string& path)
{
    std::string ext = std::filesystem::path(path).extension().string();
    std::transform(ext.begin(), ext.end(), ext.begin(),
                   [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
    return ext;
}

TriangleMesh read_by_format(const std::string& path)
{
    const std::string ext = lower_extension(path);
    if (ext == ".off") {
        const std::vector<std::byte> bytes = read_file_bytes(path);
        return parse_off(path, std::string_view(reinterpret_cast<const char*>(bytes.data()), bytes.size()));
    }
    if (ext == ".stl") return parse_stl(path, read_file_bytes(path));
    if (ext == ".obj" || ext == ".ply") {
        check_file_readable(path);
        return read_with_openmesh(path, ext == ".obj" ? "OBJ" : "PLY");
    }
    throw file_error(path, "unknown mesh format '" + ext + "' (expected .off, .obj, .ply or .stl)");
}

// ---------------------------------------------------------------------------------------------
// Edge topology

/// Union-find over vertex indices, for grouping boundary edges into loops.
class DisjointSets {
public:
    explicit DisjointSets(std::size_t n) : m_parent(n) { std::iota(m_parent.begin(), m_parent.end(), 0); }
    int find(int i)
    {
        while (m_parent[static_cast<std::size_t>(i)] != i) {
            int& p = m_parent[static_cast<std::size_t>(i)];
            p = m_parent[static_cast<std::size_t>(p)]; // path halving
            i = p;
        }
        return i;
    }
    void unite(int a, int b) { m_parent[static_cast<std::size_t>(find(a))] = find(b); }

private:
    std::vector<int> m_parent;
};

/// One use of an undirected edge by a triangle: `key` packs (min, max) vertex index, `forward` says
/// whether the triangle walks it from min to max.
struct EdgeUse {
    std::uint64_t key;
    bool forward;
    bool operator<(const EdgeUse& o) const { return key < o.key; }
};

std::vector<EdgeUse> sorted_edge_uses(const TriangleMesh& mesh)
{
    std::vector<EdgeUse> uses;
    uses.reserve(3 * mesh.triangles.size());
    for (const Eigen::Vector3i& t : mesh.triangles) {
        for (int c = 0; c < 3; ++c) {
            const auto a = static_cast<std::uint32_t>(t[c]);
            const auto b = static_cast<std::uint32_t>(t[(c + 1) % 3]);
            uses.push_back({(std::uint64_t{std::min(a, b)} << 32) | std::max(a, b), a < b});
        }
    }
    std::sort(uses.begin(), uses.end());
    return uses;
}

/// Fills the edge counts, `closed`, `consistently_oriented`, the boundary loops and their cap area.
void summarise_edges(const TriangleMesh& mesh, const Eigen::Vector3d& centre, MeshInfo& info)
{
    const std::vector<EdgeUse> uses = sorted_edge_uses(mesh);
    std::vector<std::pair<int, int>> boundary; // directed as their triangle walks them
    info.consistently_oriented = true;
    for (std::size_t i = 0; i < uses.size();) {
        std::size_t j = i;
        long long balance = 0;
        for (; j < uses.size() && uses[j].key == uses[i].key; ++j) balance += uses[j].forward ? 1 : -1;
        const std::size_t count = j - i;
        ++info.edges;
        if (count == 1) {
            const int lo = static_cast<int>(uses[i].key >> 32);
            const int hi = static_cast<int>(uses[i].key & 0xffffffffu);
            boundary.emplace_back(uses[i].forward ? lo : hi, uses[i].forward ? hi : lo);
        } else if (balance != 0) {
            info.consistently_oriented = false;
        }
        if (count > 2) ++info.non_manifold_edges;
        i = j;
    }
    info.boundary_edges = boundary.size();
    info.closed = !mesh.triangles.empty() && info.boundary_edges == 0 && info.non_manifold_edges == 0;

    DisjointSets sets(mesh.vertices.size());
    for (const auto& [a, b] : boundary) sets.unite(a, b);
    std::unordered_map<int, Eigen::Vector3d> loop_area; // by the loop's representative vertex
    for (const auto& [a, b] : boundary) {
        const Eigen::Vector3d pa = mesh.vertices[static_cast<std::size_t>(a)] - centre;
        const Eigen::Vector3d pb = mesh.vertices[static_cast<std::size_t>(b)] - centre;
        auto [it, inserted] = loop_area.try_emplace(sets.find(a), Eigen::Vector3d::Zero());
        it->second += 0.5 * pa.cross(pb);
    }
    info.boundary_loops = loop_area.size();
    for (const auto& [root, area] : loop_area) info.boundary_cap_area_mm2 += area.norm();
}

} // namespace

TriangleMesh read_mesh(const std::string& path, double mm_per_unit)
{
    if (!std::isfinite(mm_per_unit) || mm_per_unit <= 0.0)
        throw file_error(path,
                         "the scale mm_per_unit = " + std::to_string(mm_per_unit) + " must be positive and finite");
    TriangleMesh mesh = read_by_format(path);
    for (Eigen::Vector3d& p : mesh.vertices) p *= mm_per_unit;
    check_mesh(mesh, path);
    return mesh;
}

void check_mesh(const TriangleMesh& mesh, const std::string& name)
{
    if (mesh.triangles.empty())
        throw file_error(name, "has no faces (" + std::to_string(mesh.vertices.size()) +
                                   " vertices, 0 faces with 3 distinct corners): a surface mesh is needed");
    for (std::size_t v = 0; v < mesh.vertices.size(); ++v)
        if (!mesh.vertices[v].allFinite())
            throw file_error(name, "vertex " + std::to_string(v) + " has a non-finite coordinate " +
                                       format_point(mesh.vertices[v]));
    const auto n = static_cast<long long>(mesh.vertices.size());
    for (std::size_t t = 0; t < mesh.triangles.size(); ++t)
        for (int c = 0; c < 3; ++c)
            if (mesh.triangles[t][c] < 0 || mesh.triangles[t][c] >= n)
                throw file_error(name, "triangle " + std::to_string(t) + " references vertex " +
                                           std::to_string(mesh.triangles[t][c]) + ", but there are only " +
                                           std::to_string(n) + " vertices");
}

MeshInfo mesh_info(const TriangleMesh& mesh)
{
    MeshInfo info;
    info.vertices = mesh.vertices.size();
    info.triangles = mesh.triangles.size();
    if (mesh.triangles.empty()) return info;

    Eigen::AlignedBox3d box;
    for (const Eigen::Vector3i& t : mesh.triangles)
        for (int c = 0; c < 3; ++c) box.extend(mesh.vertices[static_cast<std::size_t>(t[c])]);
    info.bbox_min = box.min();
    info.bbox_max = box.max();
    // Corners relative to the box centre keep the volume's terms small: less cancellation.
    const Eigen::Vector3d centre = box.center();
    for (const Eigen::Vector3i& t : mesh.triangles) {
        const Eigen::Vector3d a = mesh.vertices[static_cast<std::size_t>(t[0])] - centre;
        const Eigen::Vector3d b = mesh.vertices[static_cast<std::size_t>(t[1])] - centre;
        const Eigen::Vector3d c = mesh.vertices[static_cast<std::size_t>(t[2])] - centre;
        info.area_mm2 += 0.5 * (b - a).cross(c - a).norm();
        info.enclosed_volume_mm3 += a.dot(b.cross(c)) / 6.0;
    }
    summarise_edges(mesh, centre, info);
    return info;
}

} // namespace vox::io
