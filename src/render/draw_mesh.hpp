#pragma once
// What the renderer draws: triangle meshes (or line sets) in world millimetres with a colour per
// vertex. Built by the caller from the surface, the tools or the element cage.

#include <Eigen/Core>

#include <cstdint>
#include <vector>

namespace vox::render {

struct DrawMesh {
    std::vector<Eigen::Vector3f> positions; ///< world mm
    std::vector<Eigen::Vector3f> normals;   ///< per vertex, unit (ignored for lines)
    std::vector<Eigen::Vector3f> colors;    ///< per vertex, linear RGB in [0, 1]
    std::vector<std::uint32_t> indices;     ///< triangles (three per), or line segments (two per)
    float alpha = 1.0f;                     ///< below 1: blended over the opaque meshes
    bool lines = false;                     ///< indices are segments, drawn unlit
    bool frames_camera = true;              ///< a picture's camera is framed on it (not on a table reaching far beyond the object)
};

/// Area-weighted vertex normals of a triangle mesh (into mesh.normals).
void compute_normals(DrawMesh& mesh);

/// Taubin smoothing (lambda 0.5, mu -0.53) of a triangle mesh's positions, for display only: a
/// marching-cubes surface on voxels shows every voxel step, which says nothing about the organ
/// (3D Slicer smooths its segmentation models the same way). Shrinks the shape very little.
void smooth_for_display(DrawMesh& mesh, int iterations);

} // namespace vox::render
