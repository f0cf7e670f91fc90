// What the mesh readers share: building triangles from polygons, and points in messages.

#include "io/mesh_readers.hpp"

#include "core/log.hpp"
#include "io/text_parsing.hpp"

#include <sstream>
#include <utility>

namespace vox::io::detail {

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

std::string too_many_corners(double corners)
{
    return "a face of " + number_text(corners) + " corners, more than the " + std::to_string(k_max_face_corners) +
           " a face may have";
}

TriangleMesh MeshBuilder::finish(const std::string& path)
{
    if (skipped_faces > 0)
        log::warn("{}: skipped {} face(s) that repeat a vertex (zero area)", path, skipped_faces);
    return std::move(mesh);
}

std::string format_point(const Eigen::Vector3d& p)
{
    std::ostringstream s;
    s << '(' << p.x() << ", " << p.y() << ", " << p.z() << ')';
    return s.str();
}

} // namespace vox::io::detail
