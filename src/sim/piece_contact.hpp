#pragma once
// The scene's "piece_contact" key as the contact model's parameters, and what a frame's contact of
// the object with itself measured (stats.json: frames' piece_contact).

#include "contact/piece_contact.hpp"
#include "io/scene.hpp"

#include <algorithm>
#include <cstddef>
#include <vector>

namespace vox::sim {

struct PieceContactFigures {
    bool enabled = false;            ///< the scene's "piece_contact" is on
    std::size_t contacts = 0;        ///< vertices pressing a face and edges under an edge this frame
    std::size_t edge_contacts = 0;   ///< of those, edges under an edge
    std::size_t tested_vertices = 0; ///< surface vertices the broad phase passed on
    double force_n = 0.0;            ///< sum of the contacts' force magnitudes at the step's end
    double ms = 0.0;                 ///< time to find them and gather them on the model
    double max_depth_mm = 0.0;       ///< the deepest contact at the step's start (interpenetration)
};

/// The deepest of `faces` and `edges` at the step's start, mm (0 when none is in).
[[nodiscard]] inline double deepest_mm(const std::vector<contact::FaceContact>& faces, const std::vector<contact::EdgeContact>& edges)
{
    double out = 0.0;
    for (const contact::FaceContact& f : faces) out = std::max(out, f.depth_mm);
    for (const contact::EdgeContact& e : edges) out = std::max(out, e.depth_mm);
    return out;
}

/// The contact parameters for a scene whose voxels are `voxel_mm` long. Deeper than a voxel is
/// not a contact (vertices arriving are caught before they are in: contact/piece_contact.hpp;
/// deeper is the far side of a thin part or gone through). Elements are tested when they come within
/// 0.9 voxel of each other (so never two of a whole object: at level 0 the nearest elements that
/// share no node are a voxel apart); apart by less than 2 % of a voxel is touching. Behind the
/// rest surface by more than half a voxel is through material.
[[nodiscard]] inline contact::PieceContactParameters piece_contact_parameters(const io::Scene& scene, double voxel_mm)
{
    contact::PieceContactParameters p;
    p.stiffness_n_per_mm = scene.piece_contact.stiffness_n_per_mm;
    p.max_depth_mm = voxel_mm;
    p.approach_mm = 0.9 * voxel_mm;
    p.skin_mm = 0.02 * voxel_mm;
    p.rest_tolerance_mm = 0.5 * voxel_mm;
    return p;
}

} // namespace vox::sim
