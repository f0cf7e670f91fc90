#include "io/mesh_writer.hpp"

#include "core/atomic_file.hpp"
#include "core/error.hpp"
#include "io/text_parsing.hpp"

#include <Eigen/Geometry>

#include <algorithm>
#include <cctype>
#include <cstdio>
#include <cstring>
#include <fstream>

namespace vox::io {
namespace {

template <class T> void put(std::ofstream& out, T value) { out.write(reinterpret_cast<const char*>(&value), sizeof(T)); }

void write_obj(std::ofstream& out, std::span<const Eigen::Vector3d> p, std::span<const Eigen::Vector3i> t)
{
    char line[128];
    out << "# VoxSculpt surface, world millimetres\n";
    for (const auto& v : p) {
        std::snprintf(line, sizeof line, "v %.9g %.9g %.9g\n", v.x(), v.y(), v.z());
        out << line;
    }
    for (const auto& f : t) out << "f " << f[0] + 1 << ' ' << f[1] + 1 << ' ' << f[2] + 1 << '\n';
}

void write_off(std::ofstream& out, std::span<const Eigen::Vector3d> p, std::span<const Eigen::Vector3i> t)
{
    char line[128];
    out << "OFF\n" << p.size() << ' ' << t.size() << " 0\n";
    for (const auto& v : p) {
        std::snprintf(line, sizeof line, "%.9g %.9g %.9g\n", v.x(), v.y(), v.z());
        out << line;
    }
    for (const auto& f : t) out << "3 " << f[0] << ' ' << f[1] << ' ' << f[2] << '\n';
}

void write_ply(std::ofstream& out, std::span<const Eigen::Vector3d> p, std::span<const Eigen::Vector3i> t,
               std::span<const std::int32_t> labels)
{
    out << "ply\nformat binary_little_endian 1.0\ncomment VoxSculpt surface, world millimetres\n"
        << "element vertex " << p.size() << "\nproperty float x\nproperty float y\nproperty float z\n";
    if (!labels.empty()) out << "property int label\n";
    out << "element face " << t.size() << "\nproperty list uchar int vertex_indices\nend_header\n";
    for (std::size_t i = 0; i < p.size(); ++i) {
        for (int a = 0; a < 3; ++a) put(out, static_cast<float>(p[i][a]));
        if (!labels.empty()) put(out, labels[i]);
    }
    for (const auto& f : t) {
        put(out, std::uint8_t{3});
        for (int a = 0; a < 3; ++a) put(out, static_cast<std::int32_t>(f[a]));
    }
}

void write_stl(std::ofstream& out, std::span<const Eigen::Vector3d> p, std::span<const Eigen::Vector3i> t)
{
    char header[80] = {};
    std::strncpy(header, "VoxSculpt surface, world millimetres", sizeof header - 1);
    out.write(header, sizeof header);
    put(out, static_cast<std::uint32_t>(t.size()));
    for (const auto& f : t) {
        const Eigen::Vector3d n = (p[f[1]] - p[f[0]]).cross(p[f[2]] - p[f[0]]).normalized();
        for (int a = 0; a < 3; ++a) put(out, static_cast<float>(n.allFinite() ? n[a] : 0.0));
        for (int k = 0; k < 3; ++k)
            for (int a = 0; a < 3; ++a) put(out, static_cast<float>(p[f[k]][a]));
        put(out, std::uint16_t{0});
    }
}

} // namespace

bool is_writable_mesh_path(const std::string& path)
{
    const std::string ext = detail::lower_extension(path);
    return ext == ".obj" || ext == ".ply" || ext == ".stl" || ext == ".off";
}

void write_mesh(const std::string& path, std::span<const Eigen::Vector3d> positions,
                std::span<const Eigen::Vector3i> triangles, std::span<const std::int32_t> labels)
{
    const std::string ext = detail::lower_extension(path);
    if (!is_writable_mesh_path(path))
        throw file_error(path, "unknown mesh format '" + ext + "' (expected .obj, .ply, .stl or .off)");
    write_atomically(path, [&](const std::filesystem::path& tmp) {
        std::ofstream out(tmp, std::ios::binary);
        if (!out) throw file_error(path, "cannot be written");
        if (ext == ".obj") write_obj(out, positions, triangles);
        if (ext == ".off") write_off(out, positions, triangles);
        if (ext == ".ply") write_ply(out, positions, triangles, labels);
        if (ext == ".stl") write_stl(out, positions, triangles);
        out.close();
        if (!out) throw file_error(path, "write failed (disk full?)");
    });
}

} // namespace vox::io
