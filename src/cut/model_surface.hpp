#pragma once
// The embedded surface moved by a mechanical model of any level, 0 included: each surface vertex
// is interpolated trilinearly in the model element holding it (level 0: its own voxel's element;
// coarser levels: the branched element the surface embedded it in). Also where contact and
// cutting look things up: the vertices of each element, the triangles of each vertex, and the
// deformed centre of any fine voxel.

#include "fem/hex_model.hpp"
#include "surface/embedded_surface.hpp"

#include <span>
#include <vector>

namespace vox::cut {

class ModelSurface {
public:
    /// `surface` must be embedded at max(model.level(), 1) in `grid`. Keeps references to all three.
    ModelSurface(const grid::BranchedGrid& grid, const fem::HexModel& model, const surface::EmbeddedSurface& surface);

    [[nodiscard]] const grid::BranchedGrid& grid() const { return m_grid; }
    [[nodiscard]] const fem::HexModel& model() const { return m_model; }
    [[nodiscard]] const surface::EmbeddedSurface& embedded() const { return m_surface; }

    /// +1, or -1 when the triangle slots' corner order gives inward world normals (a mirroring scan).
    [[nodiscard]] double outward_sign() const { return m_surface.mirrored() ? -1.0 : 1.0; }

    /// Displacement of every surface vertex slot (free slots: zero), m, from node positions (m).
    [[nodiscard]] std::vector<Eigen::Vector3d> displacements(const std::vector<Eigen::Vector3d>& node_positions) const;
    /// The deformed surface, world mm.
    [[nodiscard]] surface::SurfaceMesh mesh(const std::vector<Eigen::Vector3d>& node_positions) const;

    /// Deformed position of surface vertex slot `v`, world mm (node positions in m).
    [[nodiscard]] Eigen::Vector3d vertex_mm(std::uint32_t v, const std::vector<Eigen::Vector3d>& node_positions) const;
    /// Rest position of vertex slot `v`, world mm.
    [[nodiscard]] const Eigen::Vector3d& vertex_rest_mm(std::uint32_t v) const { return m_rest_mm[v]; }
    /// Model element holding vertex slot `v` (no_index for a free slot), and its trilinear coordinates there.
    [[nodiscard]] std::uint32_t vertex_element(std::uint32_t v) const { return m_element[v]; }
    [[nodiscard]] const Eigen::Vector3d& vertex_local(std::uint32_t v) const { return m_local[v]; }
    /// Vertex slots embedded in model element `e`.
    [[nodiscard]] std::span<const std::uint32_t> element_vertices(std::uint32_t e) const
    {
        return {m_element_vertices.data() + m_element_start[e], m_element_start[e + 1] - m_element_start[e]};
    }
    /// Triangle slots using vertex slot `v`.
    [[nodiscard]] std::span<const std::uint32_t> vertex_triangles(std::uint32_t v) const
    {
        return {m_vertex_triangles.data() + m_triangle_start[v], m_triangle_start[v + 1] - m_triangle_start[v]};
    }

    /// Model element holding alive fine voxel `v` (slot), and the voxel centre's trilinear coordinates in it.
    [[nodiscard]] std::uint32_t voxel_element(std::uint32_t v, Eigen::Vector3d& local) const;
    /// Deformed centre of alive fine voxel `v`, world mm (node positions in m).
    [[nodiscard]] Eigen::Vector3d voxel_centre_mm(std::uint32_t v, const std::vector<Eigen::Vector3d>& node_positions) const;
    /// Rest centre of fine voxel `v`, world mm.
    [[nodiscard]] Eigen::Vector3d voxel_rest_mm(std::uint32_t v) const;

    /// Deformed position (world mm) of the point with trilinear coordinates `local` in model
    /// element `e` whose rest position is `rest_mm`.
    [[nodiscard]] Eigen::Vector3d deformed_mm(std::uint32_t e, const Eigen::Vector3d& local, const Eigen::Vector3d& rest_mm,
                                              const std::vector<Eigen::Vector3d>& node_positions) const;

private:
    const grid::BranchedGrid& m_grid;
    const fem::HexModel& m_model;
    const surface::EmbeddedSurface& m_surface;
    std::vector<std::uint32_t> m_model_element; ///< per grid element of the level (level 0: voxel slot)
    std::vector<std::uint32_t> m_element;       ///< per vertex slot: model element (no_index: free)
    std::vector<Eigen::Vector3d> m_local;       ///< per vertex slot: trilinear coordinates in it
    std::vector<Eigen::Vector3d> m_rest_mm;     ///< per vertex slot: rest position, world mm
    std::vector<std::uint32_t> m_element_start, m_element_vertices;  ///< vertex slots by model element
    std::vector<std::uint32_t> m_triangle_start, m_vertex_triangles; ///< triangle slots by vertex slot
};

} // namespace vox::cut
