#pragma once
// The voxel sizes and distances every grid takes, whatever it was made from (a scan, a .vdb file,
// a voxelised mesh): one place, so the readers refuse the same things with the same numbers.

namespace vox::grid {

/// The smallest voxel edge, mm: a tenth of a micrometre. No scanner images finer (micro-CT reaches
/// a micrometre), and below it the grid's affine transform is singular in double precision
/// (OpenVDB refuses it).
inline constexpr double k_min_voxel_mm = 1e-4;
/// How far from the origin a voxel may lie, mm (1 km): far beyond any scanner or studio; near
/// 1e308 the transforms overflow.
inline constexpr double k_max_world_mm = 1e6;

} // namespace vox::grid
