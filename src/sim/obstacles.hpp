#pragma once
// The scene's obstacles (io::Obstacle) as contact shapes, and what `check` says of them. Both
// methods press their surface against them every frame (contact/obstacle.hpp); pictures and the
// viewer draw them.

#include "contact/obstacle.hpp"
#include "io/scene.hpp"
#include "grid/label_grid.hpp"

#include <string>
#include <vector>

namespace vox::sim {

/// The scene's obstacles, meshes read, scaled, turned and placed. Throws the scene's InputError
/// naming obstacles[i].mesh for a mesh that cannot be read, has no triangle or is not closed and
/// consistently oriented (its inside would not be defined).
[[nodiscard]] std::vector<contact::Obstacle> make_obstacles(const io::Scene& scene);

/// Apart from an obstacle by less than this is touching it (contact::obstacle_contact), for voxels
/// `voxel_mm` long: as for pieces (sim/piece_contact.hpp).
[[nodiscard]] inline double obstacle_skin_mm(double voxel_mm) { return 0.02 * voxel_mm; }

/// The sum of the obstacles' friction forces on the object at the contacts' points (their push
/// along the normal is the solver's pair contacts', taken at the step's end).
[[nodiscard]] Eigen::Vector3d friction_force_n(const contact::ContactResult& contact);

/// The triangles to draw for every obstacle, world mm: planes as squares around `bounds` (the
/// object's box) reaching well beyond it.
[[nodiscard]] contact::TriangleMesh obstacles_mesh(const std::vector<contact::Obstacle>& obstacles, const Eigen::AlignedBox3d& bounds);

/// One line per obstacle the object starts inside: its voxels whose surface (half a voxel beyond
/// their centre) reaches into the obstacle, how many and how deep the deepest; empty when none does.
[[nodiscard]] std::vector<std::string> obstacle_overlaps(const io::Scene& scene, const std::vector<contact::Obstacle>& obstacles,
                                                         const grid::LabelGrid& labels);

} // namespace vox::sim
