#pragma once
// A lighter copy of a big surface for drawing on a slow (software) renderer: vertices clustered
// by grid cell and facing (a cut's two walls face apart and stay apart), each cluster drawn as one
// vertex at its members' mean, triangles whose corners fall in fewer than three clusters dropped. The clustering is made once for a mesh's
// connectivity (again after a cut changes it); each frame only the means are taken.

#include "render/draw_mesh.hpp"

namespace vox::render {

class DisplayLod {
public:
    /// Clusters `mesh` with cells of `cell_mm`.
    DisplayLod(const DrawMesh& mesh, double cell_mm);

    /// Whether it was made for a mesh with this connectivity (vertex and index counts).
    [[nodiscard]] bool fits(const DrawMesh& mesh) const { return mesh.positions.size() == m_cluster.size() && mesh.indices.size() == m_indices_in; }
    /// The lighter copy of `mesh` (same connectivity as at construction, positions and colours now).
    void apply(const DrawMesh& mesh, DrawMesh& out) const;
    [[nodiscard]] std::size_t triangles() const { return m_indices.size() / 3; }

private:
    std::vector<std::uint32_t> m_cluster; ///< per vertex
    std::vector<std::uint32_t> m_count;   ///< per cluster
    std::vector<std::uint32_t> m_indices; ///< triangles over clusters
    std::size_t m_indices_in = 0;
};

/// The cell size that brings `mesh` to about `target_triangles` (a triangle count grows as
/// 1 / cell^2).
[[nodiscard]] double lod_cell_mm(const DrawMesh& mesh, std::size_t target_triangles);

} // namespace vox::render
