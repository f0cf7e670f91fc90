#include "cut/model_surface.hpp"

#include "grid/hex8.hpp"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

namespace vox::cut {

ModelSurface::ModelSurface(const grid::BranchedGrid& grid, const fem::HexModel& model, const surface::EmbeddedSurface& surface)
    : m_grid(grid), m_model(model), m_surface(surface)
{
    const int level = model.level();
    // Model element of each voxel slot (level 0) or grid element (coarser levels).
    m_model_element.assign(level == 0 ? grid.voxels().slots() : grid.level(level).elements.size(), grid::no_index);
    for (std::uint32_t e = 0; e < model.elements().size(); ++e)
        if (model.elements()[e].level == level) m_model_element[model.elements()[e].grid_element] = e;
    if (!model.mixed()) return;
    // A model of two levels: the surface lies in the fine level's elements; one outside the region
    // maps to the coarse element holding it, its coordinates scaled into the coarse cell.
    const int coarse = model.coarse_level();
    const double ratio = static_cast<double>(1 << (coarse - level));
    std::vector<std::uint32_t> coarse_model(grid.level(coarse).elements.size(), grid::no_index);
    for (std::uint32_t e = 0; e < model.elements().size(); ++e)
        if (model.elements()[e].level == coarse) coarse_model[model.elements()[e].grid_element] = e;
    m_offset.assign(m_model_element.size(), Eigen::Vector3d::Zero());
    m_scale.assign(m_model_element.size(), 1.0);
    m_fine_elements.assign(model.elements().size(), {});
    const grid::Level& fine = grid.level(level);
    for (std::uint32_t f = 0; f < fine.elements.size(); ++f) {
        if (!fine.elements[f].alive) continue;
        if (m_model_element[f] != grid::no_index) {
            m_fine_elements[m_model_element[f]].push_back(f);
            continue;
        }
        const std::uint32_t a = grid::ancestor(grid, level, f, coarse);
        const std::uint32_t e = coarse_model[a];
        if (e == grid::no_index) continue;
        m_model_element[f] = e;
        m_offset[f] = (fine.elements[f].cell.cast<double>() - grid.level(coarse).elements[a].cell.cast<double>() * ratio) / ratio;
        m_scale[f] = 1.0 / ratio;
        m_fine_elements[e].push_back(f);
    }
}

std::uint32_t ModelSurface::vertex_element(std::uint32_t v) const
{
    const surface::SurfaceVertex& vertex = m_surface.vertices()[v];
    if (vertex.users == 0) return grid::no_index;
    return m_model_element[m_model.level() == 0 ? vertex.voxel : vertex.element];
}

Eigen::Vector3d ModelSurface::vertex_local(std::uint32_t v) const
{
    const surface::SurfaceVertex& vertex = m_surface.vertices()[v];
    if (m_model.mixed()) return m_offset[vertex.element] + m_scale[vertex.element] * vertex.local;
    if (m_model.level() > 0) return vertex.local;
    return vertex.rest - grid::BranchedGrid::cell_corner_index(m_grid.voxels().coord(vertex.voxel), 0, 0);
}

Eigen::Vector3d ModelSurface::deformed_mm(std::uint32_t e, const Eigen::Vector3d& local, const Eigen::Vector3d& rest_mm,
                                          const std::vector<Eigen::Vector3d>& node_positions) const
{
    const fem::HexElement& el = m_model.elements()[e];
    Eigen::Vector3d u = Eigen::Vector3d::Zero();
    for (int c = 0; c < 8; ++c)
        u += grid::hex8_shape(c, local) * (node_positions[el.dof_node[c]] - m_model.rest_positions()[el.dof_node[c]]);
    return rest_mm + 1e3 * u;
}

Eigen::Vector3d ModelSurface::vertex_mm(std::uint32_t v, const std::vector<Eigen::Vector3d>& node_positions) const
{
    return deformed_mm(vertex_element(v), vertex_local(v), vertex_rest_mm(v), node_positions);
}

std::uint32_t ModelSurface::voxel_element(std::uint32_t v, Eigen::Vector3d& local) const
{
    const int level = m_model.level();
    const grid::Coord ijk = m_grid.voxels().coord(v);
    const Eigen::Vector3d centre(ijk.x(), ijk.y(), ijk.z());
    if (level == 0) {
        local = Eigen::Vector3d::Constant(0.5);
        return m_model_element[v];
    }
    const std::uint32_t ge = m_grid.element_of(v, level);
    local = (centre - grid::BranchedGrid::cell_corner_index(m_grid.level(level).elements[ge].cell, level, 0)) /
            static_cast<double>(1 << level);
    if (m_model.mixed()) local = m_offset[ge] + m_scale[ge] * local;
    return m_model_element[ge];
}

Eigen::Vector3d ModelSurface::voxel_rest_mm(std::uint32_t v) const
{
    const grid::Coord ijk = m_grid.voxels().coord(v);
    return m_grid.voxels().world_mm(ijk.cast<double>());
}

Eigen::Vector3d ModelSurface::voxel_centre_mm(std::uint32_t v, const std::vector<Eigen::Vector3d>& node_positions) const
{
    Eigen::Vector3d local;
    const std::uint32_t e = voxel_element(v, local);
    return deformed_mm(e, local, voxel_rest_mm(v), node_positions);
}

std::vector<Eigen::Vector3d> ModelSurface::displacements(const std::vector<Eigen::Vector3d>& node_positions) const
{
    const std::size_t slots = m_surface.vertices().size();
    std::vector<Eigen::Vector3d> out(slots, Eigen::Vector3d::Zero());
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, slots, 4096), [&](const tbb::blocked_range<std::size_t>& range) {
        for (std::size_t i = range.begin(); i != range.end(); ++i) {
            const auto v = static_cast<std::uint32_t>(i);
            const std::uint32_t e = vertex_element(v);
            if (e == grid::no_index) continue;
            const fem::HexElement& el = m_model.elements()[e];
            const Eigen::Vector3d local = vertex_local(v);
            for (int c = 0; c < 8; ++c)
                out[i] += grid::hex8_shape(c, local) * (node_positions[el.dof_node[c]] - m_model.rest_positions()[el.dof_node[c]]);
        }
    });
    return out;
}

surface::SurfaceMesh ModelSurface::mesh(const std::vector<Eigen::Vector3d>& node_positions) const
{
    surface::SurfaceMesh out = m_surface.mesh(m_grid); // rest, world mm
    const std::vector<Eigen::Vector3d> u = displacements(node_positions);
    std::size_t k = 0;
    for (std::size_t i = 0; i < u.size(); ++i)
        if (m_surface.vertices()[i].users) out.positions[k++] += u[i] * 1e3;
    return out;
}

} // namespace vox::cut
