// Surface mesh reading: the choice of reader by extension, the scaling to millimetres and the
// final check every reader's result goes through.
//
// Every format is parsed by our own reader (off_reader.cpp, obj_reader.cpp, ply_reader.cpp,
// stl_reader.cpp) rather than OpenMesh's, which accept damaged files silently (details in each
// reader): a bad vertex or index must stop the import, not change the shape.

#include "io/mesh.hpp"
#include "io/text_parsing.hpp"

#include "core/error.hpp"
#include "io/mesh_readers.hpp"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <filesystem>

namespace vox::io {
namespace {

TriangleMesh read_by_format(const std::string& path)
{
    const std::string ext = detail::lower_extension(path);
    if (ext == ".off") return detail::read_off(path);
    if (ext == ".stl") return detail::read_stl(path);
    if (ext == ".obj") return detail::read_obj(path);
    if (ext == ".ply") return detail::read_ply(path);
    throw file_error(path, "unknown mesh format '" + ext + "' (expected .off, .obj, .ply or .stl)");
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
                                       detail::format_point(mesh.vertices[v]));
    const auto n = static_cast<long long>(mesh.vertices.size());
    for (std::size_t t = 0; t < mesh.triangles.size(); ++t)
        for (int c = 0; c < 3; ++c)
            if (mesh.triangles[t][c] < 0 || mesh.triangles[t][c] >= n)
                throw file_error(name, "triangle " + std::to_string(t) + " references vertex " +
                                           std::to_string(mesh.triangles[t][c]) + ", but there are only " +
                                           std::to_string(n) + " vertices");
}

} // namespace vox::io
