#include "sim/method.hpp"

#include "core/error.hpp"
#include "core/log.hpp"

#include <cmath>

namespace vox::sim {

CutFigures& CutFigures::operator+=(const CutFigures& o)
{
    grid_update_ms += o.grid_update_ms;
    remesh_ms += o.remesh_ms;
    fem_update_ms += o.fem_update_ms;
    removed_voxels += o.removed_voxels;
    separated_faces += o.separated_faces;
    separated_voxels += o.separated_voxels;
    cut_elements += o.cut_elements;
    return *this;
}

void check_motion(const std::vector<double>& numbers, std::size_t expected)
{
    if (numbers.size() != expected)
        throw InputError("the state holds " + std::to_string(numbers.size()) + " numbers, this object's has " + std::to_string(expected));
    for (const double x : numbers)
        if (!std::isfinite(x)) throw InputError("the state holds a number that is not finite");
}

std::string newly_failed(const std::string& note, std::string& reported)
{
    if (note == reported) return {};
    reported = note; // "" again once a rebuilt solver has a working preconditioner
    if (!note.empty()) log::warn("{}", note);
    return note;
}

double enclosed_volume_mm3(const surface::SurfaceMesh& mesh)
{
    // Sum of the signed tetrahedra from the origin to each triangle; about the first vertex, so
    // that objects far from the origin lose no digits.
    if (mesh.positions.empty()) return 0.0;
    const Eigen::Vector3d o = mesh.positions.front();
    double six_v = 0.0;
    for (const Eigen::Vector3i& t : mesh.triangles)
        six_v += (mesh.positions[static_cast<std::size_t>(t[0])] - o)
                     .dot((mesh.positions[static_cast<std::size_t>(t[1])] - o).cross(mesh.positions[static_cast<std::size_t>(t[2])] - o));
    return std::abs(six_v) / 6.0; // a mirroring scan turns every triangle inward
}

} // namespace vox::sim
