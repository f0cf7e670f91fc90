// OFF reader: "OFF", then "#vertices #faces #edges", then one vertex "x y z" per line, then one
// face "n i_1 ... i_n" per line (0-based indices). Variants COFF, NOFF, STOFF... add per-line
// fields after the ones we read. https://segeval.cs.princeton.edu/public/off_format.html
//
// Parsed here rather than by OpenMesh because OpenMesh's OFF reader accepts damaged files silently
// (checked with OpenMesh 9.0): a vertex "nan" breaks its stream parse and every face is then
// dropped, and a truncated file gets made-up vertices.

#include "core/error.hpp"
#include "core/memory_limit.hpp"
#include "io/file_bytes.hpp"
#include "io/mesh_readers.hpp"
#include "io/text_parsing.hpp"

#include <algorithm>
#include <cstdint>

namespace vox::io::detail {
namespace {

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

std::string quoted(std::string_view s) { return "'" + printable(s) + "'"; }

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
        throw file_error(path, "only 3-dimensional OFF is supported, not " + printable(words[0]));
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
        if (static_cast<std::size_t>(*n) > k_max_face_corners)
            throw at_line("face " + std::to_string(f) + ": " + too_many_corners(double(*n)));
        corners.clear();
        for (long long c = 1; c <= *n; ++c) {
            const auto i = parse_integer(words[static_cast<std::size_t>(c)]);
            if (!i || *i < 0 || *i >= counts.vertices)
                throw at_line("face " + std::to_string(f) + " references vertex " + printable(words[c]) +
                              ", but there are only " + std::to_string(counts.vertices) + " vertices");
            corners.push_back(static_cast<int>(*i));
        }
        builder.add_polygon(corners);
    }
    return builder.finish(path);
}

} // namespace

TriangleMesh read_off(const std::string& path)
{
    const std::vector<std::byte> bytes = read_file_bytes(path);
    return parse_off(path, std::string_view(reinterpret_cast<const char*>(bytes.data()), bytes.size()));
}

} // namespace vox::io::detail
