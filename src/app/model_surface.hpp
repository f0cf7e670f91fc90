#pragma once
// The embedded surface moved by a mechanical model of any level, 0 included: each surface vertex
// is interpolated trilinearly in the model element holding it (level 0: its own voxel's element;
// coarser levels: the branched element the surface embedded it in).

#include "fem/hex_model.hpp"
#include "surface/embedded_surface.hpp"

#include <vector>

namespace vox::app {

class ModelSurface {
public:
    /// `surface` must be embedded at max(model.level(), 1) in `grid`.
    ModelSurface(const grid::BranchedGrid& grid, const fem::HexModel& model, const surface::EmbeddedSurface& surface);

    /// Displacement of every surface vertex slot (free slots: zero), m, from node positions (m).
    [[nodiscard]] std::vector<Eigen::Vector3d> displacements(const std::vector<Eigen::Vector3d>& node_positions) const;
    [[nodiscard]] const surface::EmbeddedSurface& embedded() const { return m_surface; }
    /// The deformed surface, world mm.
    [[nodiscard]] surface::SurfaceMesh mesh(const std::vector<Eigen::Vector3d>& node_positions) const;

private:
    const grid::BranchedGrid& m_grid;
    const fem::HexModel& m_model;
    const surface::EmbeddedSurface& m_surface;
    std::vector<std::uint32_t> m_element; ///< per vertex slot: model element (no_index: free)
    std::vector<Eigen::Vector3d> m_local; ///< per vertex slot: trilinear coordinates in it
};

} // namespace vox::app
