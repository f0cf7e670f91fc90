#pragma once
// The embedded surface moved by a mechanical model of any level, 0 included: each surface vertex
// is interpolated trilinearly in the model element holding it (level 0: its own voxel's element;
// coarser levels: the branched element the surface embedded it in). Also where contact and
// cutting look things up: the vertices of each element, the triangles of each vertex, and the
// deformed centre of any fine voxel. It holds only the map from grid to model elements: made
// anew after every cut, it costs a pass over the elements, not over the surface.

#include "fem/hex_model.hpp"
#include "surface/embedded_surface.hpp"

#include <span>
#include <vector>

namespace vox::cut {

class ModelSurface {
public:
    /// `surface` must be embedded at max(model.level(), 1) in `grid` (a model of two levels: at its
    /// fine level). Keeps references to all three.
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
    [[nodiscard]] Eigen::Vector3d vertex_rest_mm(std::uint32_t v) const { return m_grid.voxels().world_mm(m_surface.vertices()[v].rest); }
    /// Model element holding vertex slot `v` (no_index for a free slot), and its trilinear coordinates there.
    [[nodiscard]] std::uint32_t vertex_element(std::uint32_t v) const;
    [[nodiscard]] Eigen::Vector3d vertex_local(std::uint32_t v) const;
    /// Calls f(slot) for each vertex slot embedded in model element `e`.
    template <class F> void for_each_element_vertex(std::uint32_t e, F&& f) const
    {
        const std::uint32_t ge = m_model.elements()[e].grid_element;
        if (m_model.mixed())
            for (std::uint32_t fine : m_fine_elements[e])
                for (std::uint32_t v : m_surface.element_vertices(fine)) f(v);
        else if (m_model.level() == 0) m_surface.for_each_voxel_vertex(ge, f); // the element is one voxel
        else
            for (std::uint32_t v : m_surface.element_vertices(ge)) f(v);
    }
    /// Whether element `e` holds a surface vertex (without visiting them: at level 1 and up a
    /// coarse element can hold hundreds).
    [[nodiscard]] bool element_has_vertex(std::uint32_t e) const
    {
        const std::uint32_t ge = m_model.elements()[e].grid_element;
        if (m_model.mixed()) {
            for (std::uint32_t fine : m_fine_elements[e])
                if (!m_surface.element_vertices(fine).empty()) return true;
            return false;
        }
        if (m_model.level() != 0) return !m_surface.element_vertices(ge).empty();
        bool any = false;
        m_surface.for_each_voxel_vertex(ge, [&](std::uint32_t) { any = true; });
        return any;
    }
    /// Triangle slots using vertex slot `v`.
    [[nodiscard]] std::span<const std::uint32_t> vertex_triangles(std::uint32_t v) const { return m_surface.vertex_triangles(v); }

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
    /// Per grid element of the level (level 0: voxel slot): its model element. All else is the
    /// surface's own (its vertices' elements and coordinates, its lists by element and vertex),
    /// so a model rebuilt after a cut maps the surface without going over it.
    std::vector<std::uint32_t> m_model_element;
    /// A model of two levels (the surface embedded at the fine one): per fine grid element, where
    /// its cell lies in its model element's (coordinates there = offset + scale * its own), and
    /// per model element, the fine grid elements it holds.
    std::vector<Eigen::Vector3d> m_offset;
    std::vector<double> m_scale;
    std::vector<std::vector<std::uint32_t>> m_fine_elements;
};

} // namespace vox::cut
