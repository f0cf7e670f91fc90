#include "sim/obstacles.hpp"

#include "core/error.hpp"
#include "io/mesh.hpp"
#include "io/mesh_info.hpp"

#include <algorithm>
#include <cstdio>

namespace vox::sim {

std::vector<contact::Obstacle> make_obstacles(const io::Scene& scene)
{
    std::vector<contact::Obstacle> out;
    for (std::size_t i = 0; i < scene.obstacles.size(); ++i) {
        const io::Obstacle& o = scene.obstacles[i];
        const std::string key = "obstacles[" + std::to_string(i) + "]";
        switch (o.shape) {
        case io::ObstacleShape::plane:
            out.push_back(contact::Obstacle::plane(o.point_mm, o.normal));
            break;
        case io::ObstacleShape::box:
            out.push_back(contact::Obstacle::box(o.box_min_mm, o.box_max_mm));
            break;
        case io::ObstacleShape::mesh: {
            io::TriangleMesh m;
            try {
                m = io::read_mesh(o.mesh.string());
            } catch (const InputError& e) {
                throw scene.error(key + ".mesh", e.what());
            }
            const io::MeshInfo info = io::mesh_info(m);
            if (m.triangles.empty()) throw scene.error(key + ".mesh", o.mesh.string() + " has no triangle");
            if (!info.closed || !info.consistently_oriented)
                throw scene.error(key + ".mesh", o.mesh.string() + " is not a closed, consistently oriented surface (" +
                                                     std::to_string(info.boundary_edges) + " boundary and " +
                                                     std::to_string(info.non_manifold_edges) +
                                                     " non-manifold edges): an obstacle's inside must be defined");
            contact::TriangleMesh placed;
            for (const Eigen::Vector3d& p : m.vertices) placed.positions.push_back(o.position_mm + o.orientation * (o.scale * p));
            placed.triangles = m.triangles;
            if (info.enclosed_volume_mm3 < 0.0) // turned inside out: face outwards
                for (Eigen::Vector3i& t : placed.triangles) std::swap(t[1], t[2]);
            out.push_back(contact::Obstacle::mesh(std::move(placed)));
            break;
        }
        }
        out.back().friction = o.friction;
        out.back().stiffness_n_per_mm = o.stiffness_n_per_mm;
    }
    return out;
}

Eigen::Vector3d friction_force_n(const contact::ContactResult& contact)
{
    Eigen::Vector3d sum = Eigen::Vector3d::Zero();
    for (const contact::PointContact& c : contact.points) sum += c.across_force_n();
    return sum;
}

contact::TriangleMesh obstacles_mesh(const std::vector<contact::Obstacle>& obstacles, const Eigen::AlignedBox3d& bounds)
{
    contact::TriangleMesh out;
    const double extent = bounds.isEmpty() ? 100.0 : std::max(bounds.diagonal().norm(), 10.0);
    const Eigen::Vector3d centre = bounds.isEmpty() ? Eigen::Vector3d::Zero() : Eigen::Vector3d(bounds.center());
    for (const contact::Obstacle& o : obstacles) {
        const contact::TriangleMesh m = o.drawing_mesh(centre, extent);
        const int base = static_cast<int>(out.positions.size());
        out.positions.insert(out.positions.end(), m.positions.begin(), m.positions.end());
        for (const Eigen::Vector3i& t : m.triangles) out.triangles.push_back(t + Eigen::Vector3i::Constant(base));
    }
    return out;
}

std::vector<std::string> obstacle_overlaps(const io::Scene& scene, const std::vector<contact::Obstacle>& obstacles,
                                           const grid::LabelGrid& labels)
{
    std::vector<std::string> out;
    const double half = 0.5 * labels.voxel_size().minCoeff();
    for (std::size_t i = 0; i < obstacles.size(); ++i) {
        std::size_t inside = 0;
        double deepest = 0.0;
        labels.for_each_active([&](const grid::Coord& ijk, std::int32_t) {
            const double d = obstacles[i].signed_distance(labels.index_to_world(ijk.cast<double>())) - half;
            if (d < 0.0) {
                ++inside;
                deepest = std::max(deepest, -d);
            }
        });
        if (inside == 0) continue;
        char text[320];
        std::snprintf(text, sizeof text,
                      "%s: obstacles[%zu]: the object starts inside it (%zu of %llu voxels, up to %.3g mm deep); the first frames "
                      "push it out, fast where it is deep",
                      scene.source.c_str(), i, inside, static_cast<unsigned long long>(labels.active_voxel_count()), deepest);
        out.emplace_back(text);
    }
    return out;
}

} // namespace vox::sim
