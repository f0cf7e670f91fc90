#pragma once
// The elastic material of the fine voxels (the grid's condensation) and of the tetrahedra made
// from them (Is-XFEM): one type for both methods, SI units.

#include "grid/hex8.hpp"

namespace vox::grid {

struct ElasticMaterial {
    Lame lame;                     ///< Pa
    double density_kg_m3 = 1000.0; ///< kg/m^3
};

} // namespace vox::grid
