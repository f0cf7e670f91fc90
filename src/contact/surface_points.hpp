#pragma once
// Points of the object's surface with their area and outward normal, world mm, and the triangles
// between them: what the haptic thread touches. The simulation thread fills one (the surface near
// the tool, with a box tree over its triangles; the triangle list and tree grow there as needed)
// and publishes it; the haptic thread only reads it, so it never allocates.

#include "contact/mesh_ccd.hpp"

#include <Eigen/Core>

#include <algorithm>
#include <cstddef>
#include <span>
#include <vector>

namespace vox::contact {

/// The edges of `triangles`, each once (smaller index first), whether two triangles share it or
/// one has it on the border of a patch.
[[nodiscard]] inline std::vector<Eigen::Vector2i> surface_edges(std::span<const Eigen::Vector3i> triangles)
{
    std::vector<Eigen::Vector2i> out;
    out.reserve(3 * triangles.size());
    for (const Eigen::Vector3i& t : triangles)
        for (int k = 0; k < 3; ++k) out.emplace_back(std::min(t[k], t[(k + 1) % 3]), std::max(t[k], t[(k + 1) % 3]));
    const auto before = [](const Eigen::Vector2i& a, const Eigen::Vector2i& b) { return a[0] < b[0] || (a[0] == b[0] && a[1] < b[1]); };
    std::sort(out.begin(), out.end(), before);
    out.erase(std::unique(out.begin(), out.end()), out.end());
    return out;
}

struct SurfacePoints {
    double t_s = -1e300;                      ///< simulated time the positions are from
    std::size_t count = 0;                    ///< points in use (the vectors hold capacity())
    std::vector<Eigen::Vector3d> positions_mm;
    std::vector<Eigen::Vector3d> normals;     ///< outward, unit
    std::vector<double> areas_mm2;
    /// Per point, the contact's stiffness as ContactParameters::stiffness_n_per_mm (N/mm per cm^2
    /// of contact), where the material sets it (shape matching's constraint particles,
    /// docs/shape-matching.md); empty: the tool's own.
    std::vector<double> stiffness_n_per_mm;
    bool truncated = false;                   ///< more points were near than the capacity holds
    /// Surface triangles whose three corners are among the points (indices into them), and a box
    /// tree over them (a static mesh: start = end) for the continuous tool-mesh check.
    std::vector<Eigen::Vector3i> triangles;
    SweptBvh triangle_tree;
    /// The triangles' edges, each once (surface_edges): what the edge penalty presses.
    std::vector<Eigen::Vector2i> edges;

    explicit SurfacePoints(std::size_t capacity = 0)
        : positions_mm(capacity), normals(capacity), areas_mm2(capacity)
    {
    }
    [[nodiscard]] std::size_t capacity() const { return positions_mm.size(); }
};

} // namespace vox::contact
