// STL reader. Binary is an 80-byte header, a uint32 triangle count, then 50 bytes per triangle
// (normal, three corners as float32 little-endian, a uint16 attribute). Ascii is "solid name",
// facets "facet normal nx ny nz / outer loop / vertex x y z (x3) / endloop / endfacet", "endsolid".
//
// Parsed here rather than by OpenMesh because OpenMesh's STL reader accepts damaged files silently
// (checked with OpenMesh 9.0): a NaN in a binary STL is merged into another vertex, and a
// truncated binary STL reads as an empty mesh without error.

#include "core/error.hpp"
#include "io/file_bytes.hpp"
#include "io/mesh_readers.hpp"
#include "io/text_parsing.hpp"

#include <array>
#include <bit>
#include <cstdint>
#include <unordered_map>

namespace vox::io::detail {
namespace {

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

} // namespace

TriangleMesh read_stl(const std::string& path)
{
    const std::vector<std::byte> bytes = read_file_bytes(path);
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

} // namespace vox::io::detail
