#include "app/model_surface.hpp"

#include "grid/hex8.hpp"

namespace vox::app {

ModelSurface::ModelSurface(const grid::BranchedGrid& grid, const fem::HexModel& model, const surface::EmbeddedSurface& surface)
    : m_grid(grid), m_model(model), m_surface(surface)
{
    const int level = model.level();
    // Model element of each voxel slot (level 0) or grid element (coarser levels).
    std::vector<std::uint32_t> element_of(level == 0 ? grid.voxels().slots() : grid.level(level).elements.size(), grid::no_index);
    for (std::uint32_t e = 0; e < model.elements().size(); ++e) element_of[model.elements()[e].grid_element] = e;
    const auto& vertices = surface.vertices();
    m_element.assign(vertices.size(), grid::no_index);
    m_local.assign(vertices.size(), Eigen::Vector3d::Zero());
    for (std::size_t i = 0; i < vertices.size(); ++i) {
        const surface::SurfaceVertex& v = vertices[i];
        if (v.users == 0) continue;
        if (level == 0) {
            m_element[i] = element_of[v.voxel];
            m_local[i] = v.rest - grid::BranchedGrid::cell_corner_index(grid.voxels().coord(v.voxel), 0, 0);
        } else {
            m_element[i] = element_of[v.element];
            m_local[i] = v.local;
        }
    }
}

std::vector<Eigen::Vector3d> ModelSurface::displacements(const std::vector<Eigen::Vector3d>& node_positions) const
{
    std::vector<Eigen::Vector3d> out(m_element.size(), Eigen::Vector3d::Zero());
    for (std::size_t i = 0; i < m_element.size(); ++i) {
        if (m_element[i] == grid::no_index) continue;
        const fem::HexElement& el = m_model.elements()[m_element[i]];
        for (int c = 0; c < 8; ++c)
            out[i] += grid::hex8_shape(c, m_local[i]) * (node_positions[el.dof_node[c]] - m_model.rest_positions()[el.dof_node[c]]);
    }
    return out;
}

surface::SurfaceMesh ModelSurface::mesh(const std::vector<Eigen::Vector3d>& node_positions) const
{
    surface::SurfaceMesh out = m_surface.mesh(m_grid); // rest, world mm
    const std::vector<Eigen::Vector3d> u = displacements(node_positions);
    std::size_t k = 0;
    for (std::size_t i = 0; i < m_element.size(); ++i)
        if (m_surface.vertices()[i].users) out.positions[k++] += u[i] * 1e3;
    return out;
}

} // namespace vox::app
