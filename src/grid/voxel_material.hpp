#pragma once
// The mechanical material of fine voxels, as the grid's condensation needs it (SI units).

#include "grid/hex8.hpp"

namespace vox::grid {

struct VoxelMaterial {
    Lame lame;                     ///< Pa
    double density_kg_m3 = 1000.0; ///< kg/m^3
};

} // namespace vox::grid
