#pragma once
// A procedural head CT to develop bone work against when no real scan may be bundled
// (docs/phantoms.md, "skull"): a skull vault of varying thickness (outer table, diploe, inner
// table) with two orbits, brain and scalp, the scanner's head holder as a separate curved sheet,
// and small loose fragments, in Hounsfield units on anisotropic CT-like voxels. Every value is a
// partial-volume average (8 samples a voxel), so thresholds meet soft edges as on a real scan.

#include "io/volume.hpp"

#include <Eigen/Core>

namespace vox::io {

struct SkullPhantomSpec {
    /// Voxel spacing, mm (a CT's 0.9 x 0.9 in-plane, 1.5 mm slices).
    Eigen::Vector3d voxel_mm{0.9, 0.9, 1.5};
};

/// Hounsfield units of the phantom's tissues (documented in docs/phantoms.md).
namespace skull_hu {
inline constexpr double air = -1000.0;
inline constexpr double foam = -950.0;    ///< the cushion between head and holder
inline constexpr double soft = 40.0;      ///< scalp, neck
inline constexpr double brain = 35.0;
inline constexpr double diploe = 700.0;   ///< the spongy middle layer of the vault
inline constexpr double cortical = 1800.0; ///< outer and inner tables
inline constexpr double holder = 450.0;   ///< the head holder (carbon fibre and resin)
inline constexpr double fragment = 1200.0;
} // namespace skull_hu

/// The phantom as an int16 volume (slope 1, intercept 0: stored values are HU) in the LPS frame:
/// x towards the left, y posterior (the holder lies behind the head, as for a patient lying on
/// their back), z superior. Voxel (0, 0, 0) is centred at the world origin; the field is
/// 180 x 216 x 120 mm whatever the spacing. Throws InputError for a spacing outside [0.2, 5] mm.
[[nodiscard]] Volume make_skull_phantom(const SkullPhantomSpec& spec);

} // namespace vox::io
