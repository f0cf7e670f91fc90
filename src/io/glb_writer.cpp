#include "io/glb_writer.hpp"

#include "core/atomic_file.hpp"
#include "core/error.hpp"
#include "io/text_parsing.hpp"

#include <Eigen/Geometry>
#include <nlohmann/json.hpp>

#include <cstring>
#include <fstream>
#include <limits>
#include <map>

namespace vox::io {
namespace {

/// glTF's frame from LPS: +X = x, +Y = z, +Z = -y, and metres.
Eigen::Vector3f to_gltf(const Eigen::Vector3d& lps_mm)
{
    return Eigen::Vector3f(static_cast<float>(1e-3 * lps_mm.x()), static_cast<float>(1e-3 * lps_mm.z()),
                           static_cast<float>(-1e-3 * lps_mm.y()));
}

template <class T> void append(std::string& bin, const T* data, std::size_t count)
{
    bin.append(reinterpret_cast<const char*>(data), count * sizeof(T));
}

void pad(std::string& s, char with)
{
    while (s.size() % 4 != 0) s.push_back(with);
}

void put_u32(std::string& out, std::uint32_t v) { out.append(reinterpret_cast<const char*>(&v), 4); }

} // namespace

void write_glb(const std::filesystem::path& path, const std::vector<Eigen::Vector3d>& positions_mm,
               const std::vector<Eigen::Vector3i>& triangles, const std::vector<std::int32_t>& labels,
               const std::function<Eigen::Vector3d(std::int32_t)>& color_of,
               const std::function<std::string(std::int32_t)>& name_of)
{
    const std::string name = path.string();
    const std::string lower = detail::lower_case(name);
    if (lower.size() < 4 || lower.compare(lower.size() - 4, 4, ".glb") != 0) throw file_error(name, "a glTF binary file ends in .glb");
    if (triangles.empty()) throw file_error(name, "there is no triangle to write");

    // Vertices in glTF's frame, with area-weighted unit normals.
    std::vector<Eigen::Vector3f> p(positions_mm.size());
    for (std::size_t v = 0; v < p.size(); ++v) p[v] = to_gltf(positions_mm[v]);
    std::vector<Eigen::Vector3f> n(p.size(), Eigen::Vector3f::Zero());
    std::map<std::int32_t, std::vector<std::uint32_t>> by_label;
    for (const Eigen::Vector3i& t : triangles) {
        const Eigen::Vector3f normal = (p[static_cast<std::size_t>(t[1])] - p[static_cast<std::size_t>(t[0])])
                                           .cross(p[static_cast<std::size_t>(t[2])] - p[static_cast<std::size_t>(t[0])]);
        std::map<std::int32_t, int> votes;
        for (int c = 0; c < 3; ++c) {
            const auto v = static_cast<std::size_t>(t[c]);
            n[v] += normal;
            ++votes[v < labels.size() ? labels[v] : 0];
        }
        std::int32_t label = 0;
        int most = 0;
        for (const auto& [l, count] : votes)
            if (count > most) most = count, label = l;
        std::vector<std::uint32_t>& indices = by_label[label];
        for (int c = 0; c < 3; ++c) indices.push_back(static_cast<std::uint32_t>(t[c]));
    }
    for (Eigen::Vector3f& normal : n) normal = normal.norm() > 0.0f ? Eigen::Vector3f(normal.normalized()) : Eigen::Vector3f::UnitY();

    Eigen::Vector3f lo = Eigen::Vector3f::Constant(std::numeric_limits<float>::max()), hi = -lo;
    for (const Eigen::Vector3f& q : p) {
        lo = lo.cwiseMin(q);
        hi = hi.cwiseMax(q);
    }
    std::string bin;
    append(bin, p.data()->data(), 3 * p.size());
    const std::size_t normals_at = bin.size();
    append(bin, n.data()->data(), 3 * n.size());
    using json = nlohmann::json;
    json buffer_views = json::array(), accessors = json::array(), materials = json::array(), primitives = json::array();
    buffer_views.push_back({{"buffer", 0}, {"byteOffset", 0}, {"byteLength", 12 * p.size()}, {"target", 34962}});
    buffer_views.push_back({{"buffer", 0}, {"byteOffset", normals_at}, {"byteLength", 12 * n.size()}, {"target", 34962}});
    accessors.push_back({{"bufferView", 0}, {"componentType", 5126}, {"count", p.size()}, {"type", "VEC3"},
                         {"min", {lo.x(), lo.y(), lo.z()}}, {"max", {hi.x(), hi.y(), hi.z()}}});
    accessors.push_back({{"bufferView", 1}, {"componentType", 5126}, {"count", n.size()}, {"type", "VEC3"}});
    for (const auto& [label, indices] : by_label) {
        const std::size_t at = bin.size();
        append(bin, indices.data(), indices.size());
        const std::uint32_t most = *std::max_element(indices.begin(), indices.end());
        const std::uint32_t least = *std::min_element(indices.begin(), indices.end());
        buffer_views.push_back({{"buffer", 0}, {"byteOffset", at}, {"byteLength", 4 * indices.size()}, {"target", 34963}});
        accessors.push_back({{"bufferView", buffer_views.size() - 1}, {"componentType", 5125}, {"count", indices.size()},
                             {"type", "SCALAR"}, {"min", {least}}, {"max", {most}}});
        const Eigen::Vector3d c = color_of(label).cwiseMax(0.0).cwiseMin(1.0);
        materials.push_back({{"name", name_of(label)},
                             {"pbrMetallicRoughness", {{"baseColorFactor", {c.x(), c.y(), c.z(), 1.0}}, {"metallicFactor", 0.0}, {"roughnessFactor", 0.7}}}});
        primitives.push_back({{"attributes", {{"POSITION", 0}, {"NORMAL", 1}}}, {"indices", accessors.size() - 1},
                              {"material", materials.size() - 1}, {"mode", 4}});
    }
    pad(bin, '\0');
    const json document = {{"asset", {{"version", "2.0"}, {"generator", "VoxSculpt"}}},
                           {"scene", 0},
                           {"scenes", {{{"nodes", {0}}}}},
                           {"nodes", {{{"mesh", 0}, {"name", "object"}}}},
                           {"meshes", {{{"primitives", primitives}, {"name", "surface"}}}},
                           {"materials", materials},
                           {"accessors", accessors},
                           {"bufferViews", buffer_views},
                           {"buffers", {{{"byteLength", bin.size()}}}}};
    std::string text = document.dump(-1, ' ', false, json::error_handler_t::replace); // segment names may not be UTF-8
    pad(text, ' ');
    std::string glb;
    put_u32(glb, 0x46546C67); // "glTF"
    put_u32(glb, 2);
    put_u32(glb, static_cast<std::uint32_t>(12 + 8 + text.size() + 8 + bin.size()));
    put_u32(glb, static_cast<std::uint32_t>(text.size()));
    put_u32(glb, 0x4E4F534A); // "JSON"
    glb += text;
    put_u32(glb, static_cast<std::uint32_t>(bin.size()));
    put_u32(glb, 0x004E4942); // "BIN\0"
    glb += bin;
    write_atomically(path, [&](const std::filesystem::path& tmp) {
        std::ofstream out(tmp, std::ios::binary);
        out.write(glb.data(), static_cast<std::streamsize>(glb.size()));
        if (!out) throw file_error(name, "cannot be written");
    });
}

} // namespace vox::io
