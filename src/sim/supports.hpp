#pragma once
// Supports and loads on the material. A scene's constraint or load box acts on the object's
// material whose fine-voxel centres lie inside it (boundary included), the same material at every
// level, so that levels can be compared and mixed: what a level holds is decided by the voxels,
// never by where that level's nodes happen to fall.
//
// - A support holds, for each of its voxels, the corner of the voxel's own element nearest to the
//   voxel's centre (level 0: all eight corners, the voxel being the element). A held voxel layer
//   thinner than a cell is thus held at every level by the nodes beside it, a box ending inside a
//   cell is rounded to the nearer node plane, and of superimposed elements sharing a cell only the
//   one whose material the box holds is held.
// - A load's force is shared equally by its voxels, each voxel's share going to its element's
//   corners by the trilinear weights at its centre: the total force and its moment about any point
//   are the same at every level.

#include "fem/hex_model.hpp"
#include "grid/branched_grid.hpp"

#include <Eigen/Core>

#include <array>
#include <cstdint>
#include <utility>
#include <vector>

namespace vox::sim {

/// What one box holds of the elements of one level, kept per element so that a cut measures
/// again only the elements it changed (a box may hold a million voxels of a liver).
class BoxMaterial {
public:
    /// The box [lo, hi], world mm.
    BoxMaterial(const Eigen::Vector3d& lo, const Eigen::Vector3d& hi) : m_lo(lo), m_hi(hi) {}

    /// Measures the alive elements of `level` flagged in `changed` (per grid element id of the
    /// level, as HexModel takes it), or all of them when `changed` is null. A model of two levels
    /// needs both measured.
    void update(const grid::BranchedGrid& grid, int level, const std::vector<unsigned char>* changed);

    /// Voxels of alive elements in the box, as last measured.
    [[nodiscard]] std::size_t voxel_count(const fem::HexModel& model) const;
    /// The nodes the box holds as a support (each once, ascending); empty when it holds no material.
    /// A border node of a model of two levels moves with the coarse nodes it is tied to: those are
    /// held in its place.
    [[nodiscard]] std::vector<std::uint32_t> supported_nodes(const fem::HexModel& model) const;
    /// Each node's share of a load on the box's material (shares sum to 1; each node once, ascending).
    [[nodiscard]] std::vector<std::pair<std::uint32_t, double>> load_shares(const fem::HexModel& model) const;

private:
    /// Of one element: its voxels in the box, the corners nearest to them (bit c for corner c), and
    /// their trilinear weights summed per corner.
    struct Held {
        std::uint32_t voxels = 0;
        std::uint8_t corners = 0;
        std::array<double, 8> weight{};
    };
    [[nodiscard]] Held measure(const grid::BranchedGrid& grid, int level, std::uint32_t element) const;
    [[nodiscard]] const Held& held(const fem::HexElement& el) const
    {
        return m_by_level[static_cast<std::size_t>(el.level)][el.grid_element];
    }

    Eigen::Vector3d m_lo, m_hi;
    /// Per level, per grid element id (level 0: voxel slot).
    std::array<std::vector<Held>, 7> m_by_level;
};

} // namespace vox::sim
