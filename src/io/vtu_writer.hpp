#pragma once
// The finite-element mesh of a run for ParaView: VTK XML unstructured grids (.vtu, ASCII), one
// per written frame, and a .pvd collection that makes them a time series.

#include <Eigen/Core>

#include <cstdint>
#include <filesystem>
#include <string>
#include <utility>
#include <vector>

namespace vox::io {

/// One mesh: points (world mm) with vectors, cells of one VTK type with scalars.
struct VtuMesh {
    static constexpr int k_tetra = 10;      ///< VTK_TETRA
    static constexpr int k_hexahedron = 12; ///< VTK_HEXAHEDRON (corners in VTK's order)
    std::vector<Eigen::Vector3d> points;
    std::vector<std::pair<std::string, std::vector<Eigen::Vector3d>>> point_vectors; ///< name, one per point
    int cell_type = k_hexahedron;
    std::vector<std::uint32_t> connectivity; ///< 8 (hexahedra) or 4 (tetrahedra) points per cell
    std::vector<std::pair<std::string, std::vector<double>>> cell_scalars; ///< name, one per cell
    [[nodiscard]] std::size_t cell_count() const { return connectivity.size() / (cell_type == k_tetra ? 4 : 8); }
};

/// Writes `mesh` to `path` (.vtu) atomically.
void write_vtu(const VtuMesh& mesh, const std::filesystem::path& path);

/// Writes the ParaView collection `path` (.pvd) of `frames`: (time in s, .vtu file name relative
/// to the .pvd's folder).
void write_pvd(const std::vector<std::pair<double, std::string>>& frames, const std::filesystem::path& path);

} // namespace vox::io
