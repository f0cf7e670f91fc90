#include "cut/model_surface.hpp"

#include "grid/hex8.hpp"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

namespace vox::cut {
namespace {

/// CSR grouping of `item_count` items by key (keys < key_count; no_index skipped).
void group(const std::vector<std::uint32_t>& key_of_item, std::size_t key_count, std::vector<std::uint32_t>& start,
           std::vector<std::uint32_t>& items)
{
    start.assign(key_count + 1, 0);
    for (std::uint32_t k : key_of_item)
        if (k != grid::no_index) ++start[k + 1];
    for (std::size_t k = 0; k < key_count; ++k) start[k + 1] += start[k];
    items.resize(start.back());
    std::vector<std::uint32_t> fill(start.begin(), start.end() - 1);
    for (std::uint32_t i = 0; i < key_of_item.size(); ++i)
        if (key_of_item[i] != grid::no_index) items[fill[key_of_item[i]]++] = i;
}

} // namespace

ModelSurface::ModelSurface(const grid::BranchedGrid& grid, const fem::HexModel& model, const surface::EmbeddedSurface& surface)
    : m_grid(grid), m_model(model), m_surface(surface)
{
    const int level = model.level();
    // Model element of each voxel slot (level 0) or grid element (coarser levels).
    m_model_element.assign(level == 0 ? grid.voxels().slots() : grid.level(level).elements.size(), grid::no_index);
    for (std::uint32_t e = 0; e < model.elements().size(); ++e) m_model_element[model.elements()[e].grid_element] = e;
    const auto& vertices = surface.vertices();
    m_element.assign(vertices.size(), grid::no_index);
    m_local.assign(vertices.size(), Eigen::Vector3d::Zero());
    m_rest_mm.assign(vertices.size(), Eigen::Vector3d::Zero());
    // In parallel: a skull's surface has a few hundred thousand vertices, and a drill rebuilds
    // this every frame it takes a voxel.
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, vertices.size(), 4096), [&](const tbb::blocked_range<std::size_t>& range) {
        for (std::size_t i = range.begin(); i != range.end(); ++i) {
            const surface::SurfaceVertex& v = vertices[i];
            if (v.users == 0) continue;
            m_rest_mm[i] = grid.voxels().world_mm(v.rest);
            if (level == 0) {
                m_element[i] = m_model_element[v.voxel];
                m_local[i] = v.rest - grid::BranchedGrid::cell_corner_index(grid.voxels().coord(v.voxel), 0, 0);
            } else {
                m_element[i] = m_model_element[v.element];
                m_local[i] = v.local;
            }
        }
    });
    group(m_element, model.elements().size(), m_element_start, m_element_vertices);
    // Triangles by vertex: each triangle listed under its three vertices.
    const auto& triangles = surface.triangles();
    m_triangle_start.assign(vertices.size() + 1, 0);
    for (const auto& tri : triangles)
        if (tri[0] != grid::no_index)
            for (std::uint32_t v : tri) ++m_triangle_start[v + 1];
    for (std::size_t v = 0; v < vertices.size(); ++v) m_triangle_start[v + 1] += m_triangle_start[v];
    m_vertex_triangles.resize(m_triangle_start.back());
    std::vector<std::uint32_t> fill(m_triangle_start.begin(), m_triangle_start.end() - 1);
    for (std::uint32_t k = 0; k < triangles.size(); ++k)
        if (triangles[k][0] != grid::no_index)
            for (std::uint32_t v : triangles[k]) m_vertex_triangles[fill[v]++] = k;
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
    return deformed_mm(m_element[v], m_local[v], m_rest_mm[v], node_positions);
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

} // namespace vox::cut
