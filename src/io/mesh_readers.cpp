// What the mesh readers share: building triangles from polygons, and text parsing.

#include "io/mesh_readers.hpp"

#include "core/log.hpp"

#include <charconv>
#include <sstream>
#include <system_error>
#include <utility>

namespace vox::io::detail {
namespace {

bool is_space(char c) { return c == ' ' || c == '\t' || c == '\r' || c == '\n' || c == '\v' || c == '\f'; }

} // namespace

void MeshBuilder::add_polygon(const std::vector<int>& corners)
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

TriangleMesh MeshBuilder::finish(const std::string& path)
{
    if (skipped_faces > 0)
        log::warn("{}: skipped {} face(s) that repeat a vertex (zero area)", path, skipped_faces);
    return std::move(mesh);
}

std::optional<double> parse_double(std::string_view s)
{
    if (!s.empty() && s.front() == '+') s.remove_prefix(1); // from_chars rejects a leading '+'
    double v = 0.0;
    const auto [end, ec] = std::from_chars(s.data(), s.data() + s.size(), v);
    if (ec != std::errc() || end != s.data() + s.size() || s.empty()) return std::nullopt;
    return v;
}

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

std::string format_point(const Eigen::Vector3d& p)
{
    std::ostringstream s;
    s << '(' << p.x() << ", " << p.y() << ", " << p.z() << ')';
    return s.str();
}

} // namespace vox::io::detail
