#pragma once
// The labelled fine voxels of an object: an OpenVDB int32 grid plus its index-to-world transform.
// This header keeps OpenVDB out of its includers; grid/label_grid_vdb.hpp gives the grid itself to
// the few translation units that need OpenVDB's tools.

#include <Eigen/Core>

#include <cstdint>
#include <filesystem>
#include <functional>
#include <map>
#include <memory>
#include <string>

namespace vox::grid {

/// Voxel index (i, j, k) in the grid's index space.
using Coord = Eigen::Vector3i;

/// Inclusive index bounding box; empty when min > max on any axis.
struct IndexBox {
    Coord min{0, 0, 0};
    Coord max{-1, -1, -1};
    [[nodiscard]] bool empty() const { return (min.array() > max.array()).any(); }
};

/// Active voxels carry a non-zero material label; inactive voxels are background (label 0).
/// Voxel (i, j, k) has its centre at index_to_world() * (i, j, k, 1), world millimetres (LPS).
class LabelGrid {
public:
    /// An empty grid with the given index-to-world transform (affine 4x4, world mm).
    explicit LabelGrid(const Eigen::Matrix4d& index_to_world = Eigen::Matrix4d::Identity());
    ~LabelGrid();
    LabelGrid(LabelGrid&&) noexcept;
    LabelGrid& operator=(LabelGrid&&) noexcept;
    LabelGrid(const LabelGrid&) = delete;
    LabelGrid& operator=(const LabelGrid&) = delete;
    [[nodiscard]] LabelGrid clone() const;

    [[nodiscard]] Eigen::Matrix4d index_to_world() const;
    /// Voxel edge lengths along the index axes, mm.
    [[nodiscard]] Eigen::Vector3d voxel_size() const;
    /// World position (mm) of voxel centre (i, j, k); fractional indices allowed.
    [[nodiscard]] Eigen::Vector3d index_to_world(const Eigen::Vector3d& ijk) const;

    /// Sets voxel (i, j, k) to `label`; label 0 makes the voxel inactive. Not thread-safe.
    void set(const Coord& ijk, std::int32_t label);
    /// The label of voxel (i, j, k), 0 when inactive.
    [[nodiscard]] std::int32_t get(const Coord& ijk) const;

    [[nodiscard]] std::uint64_t active_voxel_count() const;
    /// Tight index bounding box of the active voxels.
    [[nodiscard]] IndexBox index_bounds() const;
    /// Number of active voxels per label.
    [[nodiscard]] std::map<std::int32_t, std::uint64_t> label_histogram() const;
    /// Calls f(ijk, label) for every active voxel, in no particular order.
    void for_each_active(const std::function<void(const Coord&, std::int32_t)>& f) const;

    /// Free-form metadata kept in the .vdb file (e.g. "source" = the scan it came from).
    void set_metadata(const std::string& key, const std::string& value);
    [[nodiscard]] std::string metadata(const std::string& key) const;
    /// Takes every string metadata of `from` (its source, scan size, segments) for a grid derived from it.
    void copy_metadata(const LabelGrid& from);

    /// Writes an OpenVDB file holding this one grid (named "labels"), atomically.
    void save(const std::filesystem::path& path) const;
    /// Reads the first int32 grid of an OpenVDB file (or the grid named "labels" if several).
    /// Throws InputError naming the file when missing, unreadable, or holding no int32 grid.
    [[nodiscard]] static LabelGrid load(const std::filesystem::path& path);

    struct Impl;
    [[nodiscard]] Impl& impl() { return *m_impl; }
    [[nodiscard]] const Impl& impl() const { return *m_impl; }

private:
    std::unique_ptr<Impl> m_impl;
};

} // namespace vox::grid
