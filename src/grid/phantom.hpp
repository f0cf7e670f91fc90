#pragma once
// Procedural test objects with exact, documented sizes (docs/phantoms.md). Every phantom puts its
// first voxel's centre, index (0, 0, 0), at the world origin; the grid's axes are the world axes;
// all voxels carry label 1. Sizes must be whole numbers of voxels.

#include "grid/label_grid.hpp"

#include <Eigen/Core>

#include <string>

namespace vox::grid {

enum class PhantomShape { beam, block, sphere, cylinder, utube };

/// Sizes in millimetres; only the fields of the chosen shape are used.
struct PhantomSpec {
    PhantomShape shape = PhantomShape::beam;
    Eigen::Vector3d size_mm{200.0, 10.0, 10.0}; ///< beam, block: full extents along x, y, z
    double radius_mm = 10.0;                    ///< sphere, cylinder
    double length_mm = 60.0;                    ///< cylinder: extent along x (its axis)
    double leg_mm = 3.0;                        ///< utube: width (x) of each leg, thickness of the base
    double gap_mm = 2.0;                        ///< utube: distance (x) between the legs
    double height_mm = 16.0;                    ///< utube: total height (z)
    double depth_mm = 3.0;                      ///< utube: extent along y
    double voxel_mm = 1.0;                      ///< voxel edge
};

/// The documented defaults of a shape (beam 200 x 10 x 10, block 20 x 20 x 20, sphere radius 10,
/// cylinder radius 5 length 60, utube leg 3 gap 2 height 16 depth 3; voxel 1 mm).
[[nodiscard]] PhantomSpec default_phantom(PhantomShape shape);
[[nodiscard]] PhantomShape parse_phantom_shape(const std::string& name); ///< throws InputError
[[nodiscard]] const char* phantom_shape_name(PhantomShape shape);

/// Voxelises the phantom. Throws InputError for a non-positive size, a size that is not a whole
/// number of voxels (to 1e-6 relative), or a grid larger than the memory limit.
[[nodiscard]] LabelGrid make_phantom(const PhantomSpec& spec);

} // namespace vox::grid
