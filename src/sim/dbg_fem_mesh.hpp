#pragma once
// The branched grid's finite-element mesh as ParaView reads it (io/vtu_writer.hpp): its
// hexahedra where they are now, node displacement and velocity, and per element its level, piece,
// dominant label and label fractions, plastic strain, water content and von Mises stress.

#include "io/vtu_writer.hpp"

namespace vox::sim {

class DbgSimulation;

/// The von Mises stress is the element's at its material's centroid: the corotational small
/// strain of the deformation gradient there, less its plastic strain, through Hooke's law with
/// its material's Lame constants scaled by its water content. (Partial elements' stiffness is
/// condensed from their voxels; their centroid stress is this same approximation.)
[[nodiscard]] io::VtuMesh dbg_fem_mesh(const DbgSimulation& sim);

} // namespace vox::sim
