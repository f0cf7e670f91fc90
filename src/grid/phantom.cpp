#include "grid/phantom.hpp"

#include "core/error.hpp"
#include "core/memory_limit.hpp"

#include <cmath>
#include <functional>

namespace vox::grid {
namespace {

/// Number of voxels of edge h in `size` mm, which must be a whole number (to 1e-6 relative).
int voxel_count(const char* what, double size, double h)
{
    if (!(size > 0.0) || !std::isfinite(size))
        throw InputError(std::string("phantom: ") + what + " must be positive, got " + std::to_string(size));
    const double n = std::round(size / h);
    if (n < 1.0 || std::abs(n * h - size) > 1e-6 * size)
        throw InputError(std::string("phantom: ") + what + " = " + std::to_string(size) +
                         " mm is not a whole number of " + std::to_string(h) + " mm voxels");
    if (n > 1e6) throw InputError(std::string("phantom: ") + what + " needs more than a million voxels");
    return static_cast<int>(n);
}

/// Fills voxels of the n[0] x n[1] x n[2] box for which inside(i, j, k) holds.
LabelGrid fill(const Eigen::Vector3i& n, double h, const std::function<bool(int, int, int)>& inside)
{
    check_allocation("phantom", static_cast<std::uint64_t>(n[0]) * static_cast<std::uint64_t>(n[1]) *
                                    static_cast<std::uint64_t>(n[2]),
                     4);
    Eigen::Matrix4d t = Eigen::Matrix4d::Identity();
    t.topLeftCorner<3, 3>() *= h;
    LabelGrid grid(t);
    for (int k = 0; k < n[2]; ++k)
        for (int j = 0; j < n[1]; ++j)
            for (int i = 0; i < n[0]; ++i)
                if (inside(i, j, k)) grid.set({i, j, k}, 1);
    return grid;
}

} // namespace

PhantomSpec default_phantom(PhantomShape shape)
{
    PhantomSpec s;
    s.shape = shape;
    if (shape == PhantomShape::block) s.size_mm = {20.0, 20.0, 20.0};
    if (shape == PhantomShape::cylinder) s.radius_mm = 5.0;
    return s;
}

PhantomShape parse_phantom_shape(const std::string& name)
{
    for (auto s : {PhantomShape::beam, PhantomShape::block, PhantomShape::sphere, PhantomShape::cylinder,
                   PhantomShape::utube})
        if (name == phantom_shape_name(s)) return s;
    throw InputError("phantom: unknown shape '" + name + "' (expected beam, block, sphere, cylinder or utube)");
}

const char* phantom_shape_name(PhantomShape shape)
{
    switch (shape) {
    case PhantomShape::beam: return "beam";
    case PhantomShape::block: return "block";
    case PhantomShape::sphere: return "sphere";
    case PhantomShape::cylinder: return "cylinder";
    case PhantomShape::utube: return "utube";
    }
    return "?";
}

LabelGrid make_phantom(const PhantomSpec& s)
{
    const double h = s.voxel_mm;
    if (!(h > 0.0) || !std::isfinite(h)) throw InputError("phantom: voxel_mm must be positive, got " + std::to_string(h));

    switch (s.shape) {
    case PhantomShape::beam:
    case PhantomShape::block: {
        const Eigen::Vector3i n(voxel_count("size_mm[0]", s.size_mm[0], h), voxel_count("size_mm[1]", s.size_mm[1], h),
                                voxel_count("size_mm[2]", s.size_mm[2], h));
        return fill(n, h, [](int, int, int) { return true; });
    }
    case PhantomShape::sphere: {
        // n voxels across the diameter; the centre sits midway between the first and last voxel
        // centres, and a voxel belongs to the sphere when its centre is in the closed ball.
        const int n = voxel_count("2 * radius_mm", 2.0 * s.radius_mm, h);
        const double c = 0.5 * (n - 1), r = s.radius_mm / h;
        return fill({n, n, n}, h, [=](int i, int j, int k) {
            return (i - c) * (i - c) + (j - c) * (j - c) + (k - c) * (k - c) <= r * r;
        });
    }
    case PhantomShape::cylinder: {
        const int nx = voxel_count("length_mm", s.length_mm, h);
        const int n = voxel_count("2 * radius_mm", 2.0 * s.radius_mm, h);
        const double c = 0.5 * (n - 1), r = s.radius_mm / h;
        return fill({nx, n, n}, h, [=](int, int j, int k) { return (j - c) * (j - c) + (k - c) * (k - c) <= r * r; });
    }
    case PhantomShape::utube: {
        // A U open upwards: a base of thickness `leg` along the bottom, two legs rising from it.
        const int leg = voxel_count("leg_mm", s.leg_mm, h);
        const int gap = voxel_count("gap_mm", s.gap_mm, h);
        const int height = voxel_count("height_mm", s.height_mm, h);
        const int depth = voxel_count("depth_mm", s.depth_mm, h);
        if (height <= leg) throw InputError("phantom: utube height_mm must exceed leg_mm (the base thickness)");
        return fill({2 * leg + gap, depth, height}, h,
                    [=](int i, int, int k) { return k < leg || i < leg || i >= leg + gap; });
    }
    }
    throw InputError("phantom: unknown shape");
}

} // namespace vox::grid
