#pragma once
// OpenVDB access to a LabelGrid, for the translation units that run OpenVDB tools on it.
// Include sparingly: OpenVDB headers are heavy.

#include "grid/label_grid.hpp"

#include <openvdb/openvdb.h>

namespace vox::grid {

struct LabelGrid::Impl {
    openvdb::Int32Grid::Ptr grid;
    openvdb::Int32Grid::Accessor accessor; ///< for single-threaded set/get through LabelGrid
    explicit Impl(openvdb::Int32Grid::Ptr g) : grid(std::move(g)), accessor(grid->getAccessor()) {}
    void reset(openvdb::Int32Grid::Ptr g)
    {
        grid = std::move(g);
        accessor = grid->getAccessor();
    }
};

/// The OpenVDB grid behind `labels` (shared, not copied).
[[nodiscard]] openvdb::Int32Grid::Ptr vdb_grid(const LabelGrid& labels);
/// Wraps an OpenVDB int32 grid (background 0; active voxels = labelled material).
[[nodiscard]] LabelGrid from_vdb(openvdb::Int32Grid::Ptr grid);

/// OpenVDB transforms use row vectors; these convert to and from our column-vector 4x4.
[[nodiscard]] openvdb::math::Transform::Ptr to_vdb_transform(const Eigen::Matrix4d& index_to_world);
[[nodiscard]] Eigen::Matrix4d from_vdb_transform(const openvdb::math::Transform& xform);

/// Registers OpenVDB's grid types once (safe to call repeatedly, from any thread).
void ensure_openvdb_initialized();

} // namespace vox::grid
