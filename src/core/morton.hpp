#pragma once
// Morton (Z-order) codes: the bits of x, y, z interleaved, x lowest. Within a cell of 2^L voxels
// per axis, the voxels of the i-th octree node at level l occupy the code interval
// [i * 8^l, (i + 1) * 8^l) (Jerabkova et al. 2010, equation 6), so full octree sub-nodes are
// found as code intervals without building an octree.

#include <cstdint>

namespace vox {

/// Interleaves the low 21 bits of x, y and z: code = sum_l (4 z_l + 2 y_l + x_l) 8^l.
[[nodiscard]] constexpr std::uint64_t morton_encode(std::uint32_t x, std::uint32_t y, std::uint32_t z)
{
    auto spread = [](std::uint64_t v) {
        v &= 0x1fffff;
        v = (v | v << 32) & 0x1f00000000ffffULL;
        v = (v | v << 16) & 0x1f0000ff0000ffULL;
        v = (v | v << 8) & 0x100f00f00f00f00fULL;
        v = (v | v << 4) & 0x10c30c30c30c30c3ULL;
        v = (v | v << 2) & 0x1249249249249249ULL;
        return v;
    };
    return spread(x) | spread(y) << 1 | spread(z) << 2;
}

/// Inverse of morton_encode for one axis: the bits of `code` at positions axis, axis + 3, ...
[[nodiscard]] constexpr std::uint32_t morton_decode_axis(std::uint64_t code, int axis)
{
    std::uint64_t v = (code >> axis) & 0x1249249249249249ULL;
    v = (v | v >> 2) & 0x10c30c30c30c30c3ULL;
    v = (v | v >> 4) & 0x100f00f00f00f00fULL;
    v = (v | v >> 8) & 0x1f0000ff0000ffULL;
    v = (v | v >> 16) & 0x1f00000000ffffULL;
    v = (v | v >> 32) & 0x1fffff;
    return static_cast<std::uint32_t>(v);
}

} // namespace vox
