#pragma once
// The fine level of the branched grid: the object's voxels in Morton order, each with its label
// and material, and which of the faces between face-adjacent voxels are connected (all at
// import; a cut in "separate" mode disconnects faces without removing voxels).

#include "grid/coord_map.hpp"
#include "grid/label_grid.hpp"

#include <array>
#include <cstdint>
#include <functional>
#include <unordered_set>
#include <vector>

namespace vox::grid {

class FineVoxels {
public:
    static constexpr std::uint32_t missing = CoordMap::missing;

    /// Takes the active voxels of `labels`; `material_of(label)` gives each voxel's material index.
    /// Throws InputError when there is no voxel or the object spans more than 2^21 voxels on an axis.
    FineVoxels(const LabelGrid& labels, const std::function<std::int32_t(std::int32_t)>& material_of);

    /// Number of voxel slots (removed voxels keep their slot; see alive()).
    [[nodiscard]] std::uint32_t slots() const { return static_cast<std::uint32_t>(m_codes.size()); }
    [[nodiscard]] std::uint32_t alive_count() const { return m_alive_count; }
    [[nodiscard]] bool alive(std::uint32_t v) const { return m_alive[v] != 0; }

    /// Index of the voxel at `ijk` (source index space), or `missing` (never present or removed).
    [[nodiscard]] std::uint32_t find(const Coord& ijk) const;
    /// Index of the voxel whose Morton code (see code()) is `code`, or `missing`.
    [[nodiscard]] std::uint32_t find_code(std::uint64_t code) const;
    /// The up to six voxels face-connected to v: (slot, direction 2 axis + (1 if on the +side)).
    template <class F> void for_each_link(std::uint32_t v, F&& f) const
    {
        for (int axis = 0; axis < 3; ++axis) {
            const std::uint32_t down = m_neighbours[v][2 * axis];
            if (down != missing && !face_disconnected(down, axis)) f(down, 2 * axis);
            const std::uint32_t up = m_neighbours[v][2 * axis + 1];
            if (up != missing && !face_disconnected(v, axis)) f(up, 2 * axis + 1);
        }
    }
    /// Source index (i, j, k) of voxel v: the coarse cell at level L is (i >> L, j >> L, k >> L).
    [[nodiscard]] Coord coord(std::uint32_t v) const { return m_coords[v]; }
    /// Morton code of v's index relative to origin(); slots are sorted by it.
    [[nodiscard]] std::uint64_t code(std::uint32_t v) const { return m_codes[v]; }
    [[nodiscard]] std::int32_t label(std::uint32_t v) const { return m_labels[v]; }
    [[nodiscard]] std::int32_t material(std::uint32_t v) const { return m_materials[v]; }
    /// A multiple of 64 per axis at or below every voxel index, so that cells of every level
    /// (up to 6) keep their boundaries when indices are taken relative to it.
    [[nodiscard]] const Coord& origin() const { return m_origin; }
    [[nodiscard]] const Eigen::Matrix4d& index_to_world() const { return m_index_to_world; }
    /// A point of the source index space (a voxel's centre is its integer coordinate) in world mm.
    [[nodiscard]] Eigen::Vector3d world_mm(const Eigen::Vector3d& index) const
    {
        return m_index_to_world.topLeftCorner<3, 3>() * index + m_index_to_world.topRightCorner<3, 1>();
    }
    /// Fine voxel edges in metres (the grid's mechanics are SI).
    [[nodiscard]] const Eigen::Vector3d& voxel_size_m() const { return m_voxel_size_m; }

    /// The voxel across the face of v on the +axis side, if present and the face is connected.
    [[nodiscard]] std::uint32_t connected_neighbour(std::uint32_t v, int axis) const;

    /// True when the face between v and its +axis neighbour was disconnected.
    [[nodiscard]] bool face_disconnected(std::uint32_t v, int axis) const
    {
        return !m_disconnected.empty() && m_disconnected.count(4 * std::uint64_t{v} + static_cast<std::uint64_t>(axis));
    }
    /// Removes voxel v (no-op when already removed).
    void remove(std::uint32_t v);
    /// Disconnects the face between v and its +axis neighbour.
    void disconnect(std::uint32_t v, int axis);

private:
    [[nodiscard]] std::uint64_t key(const Coord& ijk) const;

    Coord m_origin;
    Eigen::Matrix4d m_index_to_world;
    Eigen::Vector3d m_voxel_size_m;
    std::vector<std::uint64_t> m_codes;
    std::vector<Coord> m_coords;
    std::vector<std::int32_t> m_labels;
    std::vector<std::int32_t> m_materials;
    std::vector<std::uint8_t> m_alive;
    /// Present face neighbours of each voxel, in direction order (-x, +x, -y, +y, -z, +z).
    std::vector<std::array<std::uint32_t, 6>> m_neighbours;
    std::uint32_t m_alive_count = 0;
    /// Slot lookup by Morton code: 8^3-voxel bricks (code >> 9) found by hash, then a dense
    /// table of 512 slots per brick. Neighbour queries stay within a few cache lines, unlike a
    /// hash over every voxel.
    [[nodiscard]] std::uint32_t slot_of(std::uint64_t code) const
    {
        const std::uint32_t brick = m_bricks.find(code >> 9);
        return brick == CoordMap::missing ? missing : m_brick_slots[(std::size_t{brick} << 9) | (code & 511)];
    }
    CoordMap m_bricks;
    std::vector<std::uint32_t> m_brick_slots;
    std::unordered_set<std::uint64_t> m_disconnected;  ///< 4 * slot + axis of disconnected +axis faces
};

} // namespace vox::grid
