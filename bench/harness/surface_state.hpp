#pragma once
// The deformed surface of a branched-grid run by vertex key (the same vertices at every level,
// since the surface follows the voxels): what the benches compare between levels.

#include "sim/dbg_method.hpp"

#include <Eigen/Core>

#include <cstdint>
#include <map>

namespace vox::bench {

struct SurfaceState {
    std::map<std::uint64_t, Eigen::Vector3d> displacement_mm; ///< surface vertex key -> mm
    std::map<std::uint64_t, Eigen::Vector3d> rest_mm;         ///< surface vertex key -> world mm
};

[[nodiscard]] SurfaceState surface_state(const sim::DbgMethod& method);

} // namespace vox::bench
