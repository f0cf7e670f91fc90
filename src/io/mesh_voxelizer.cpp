// Mesh voxelisation. OpenVDB's MeshToVolume.h is heavy to compile: keep it in this file only.

#include "io/mesh_voxelizer.hpp"

#include "core/error.hpp"
#include "core/log.hpp"
#include "core/memory_limit.hpp"
#include "core/progress.hpp"
#include "grid/voxel_limits.hpp"
#include "io/winding_number.hpp"

#include <openvdb/openvdb.h>
#include <openvdb/tools/MeshToVolume.h>
#include <spdlog/fmt/fmt.h>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <vector>

namespace vox::io {
namespace {

/// The voxel centres (i h, j h, k h) inside the mesh's bounding box: i in [lo.x, lo.x + dims.x).
struct IndexRange {
    Eigen::Vector3i lo = Eigen::Vector3i::Zero();
    Eigen::Vector3i dims = Eigen::Vector3i::Zero();

    [[nodiscard]] std::uint64_t voxel_count() const
    {
        return static_cast<std::uint64_t>(dims.x()) * static_cast<std::uint64_t>(dims.y()) *
               static_cast<std::uint64_t>(dims.z());
    }
};

/// Index range of the bounding box at voxel size h, refused before anything is allocated when
/// the coordinates leave OpenVDB's int32 index space or the voxels (4 bytes each) the memory limit.
IndexRange bbox_index_range(const MeshInfo& info, double h, const std::string& name)
{
    const Eigen::Vector3d lo = (info.bbox_min / h).array().ceil();
    const Eigen::Vector3d hi = (info.bbox_max / h).array().floor();
    constexpr double k_max_index = 1 << 30;
    if (lo.cwiseAbs().maxCoeff() > k_max_index || hi.cwiseAbs().maxCoeff() > k_max_index)
        throw file_error(
            name, fmt::format("voxel size {:g} mm is too small for coordinates up to {:g} mm", h,
                              std::max(info.bbox_min.cwiseAbs().maxCoeff(), info.bbox_max.cwiseAbs().maxCoeff())));
    const Eigen::Vector3d dims = (hi - lo).array().max(-1.0) + 1.0;
    // Checked in floating point first: the exact product of three int32 sizes can overflow 64 bits.
    const double count = dims.prod();
    constexpr double k_huge = 9.0e18;
    check_allocation(fmt::format("{} at voxel size {:g} mm ({:.0f} x {:.0f} x {:.0f} voxels)", name, h, dims.x(),
                                 dims.y(), dims.z()),
                     count < k_huge ? static_cast<std::uint64_t>(count) : std::numeric_limits<std::uint64_t>::max(), 4);
    return {lo.cast<int>(), dims.cast<int>()};
}

/// A sheet with large holes (a half-pipe, a bowl) has no inside to fill; refuse it with the
/// numbers that show it rather than return some arbitrary solid.
void check_encloses_volume(const MeshInfo& info, const VoxelizeOptions& options)
{
    const double fraction = info.boundary_cap_area_mm2 / info.area_mm2;
    if (!(fraction > options.max_cap_area_fraction)) return;
    throw file_error(options.name,
                     fmt::format("the mesh is open and encloses no volume: capping its {} boundary loop(s) ({} "
                                 "boundary edges) would take {:.4g} mm^2, {:.0f}% of its {:.4g} mm^2 surface (a "
                                 "scan with holes needs at most {:.0f}%)",
                                 info.boundary_loops, info.boundary_edges, info.boundary_cap_area_mm2, 100.0 * fraction,
                                 info.area_mm2, 100.0 * options.max_cap_area_fraction));
}

Eigen::Matrix4d scaling(double h)
{
    Eigen::Matrix4d m = Eigen::Matrix4d::Identity();
    m.topLeftCorner<3, 3>() *= h;
    return m;
}

/// Inside = negative signed distance, from OpenVDB's narrow-band level set whose interior (tiles and
/// inactive voxels beyond the band) OpenVDB has already sign-flood-filled.
grid::LabelGrid voxelize_level_set(const TriangleMesh& mesh, double h, const VoxelizeOptions& options)
{
    openvdb::initialize();
    std::vector<openvdb::Vec3s> points;
    points.reserve(mesh.vertices.size());
    for (const Eigen::Vector3d& p : mesh.vertices) points.emplace_back(p.x(), p.y(), p.z());
    std::vector<openvdb::Vec3I> triangles;
    triangles.reserve(mesh.triangles.size());
    for (const Eigen::Vector3i& t : mesh.triangles)
        triangles.emplace_back(static_cast<openvdb::Index32>(t[0]), static_cast<openvdb::Index32>(t[1]),
                               static_cast<openvdb::Index32>(t[2]));

    // A linear transform of scale h puts voxel (i, j, k)'s centre at world (i h, j h, k h).
    const auto transform = openvdb::math::Transform::createLinearTransform(h);
    constexpr float k_half_width_voxels = 3.0f;
    const openvdb::FloatGrid::Ptr sdf =
        openvdb::tools::meshToLevelSet<openvdb::FloatGrid>(*transform, points, triangles, k_half_width_voxels);

    grid::LabelGrid labels(scaling(h));
    for (auto it = sdf->cbeginValueAll(); it; ++it) {
        if (!(*it < 0.0f)) continue;
        openvdb::CoordBBox box;
        it.getBoundingBox(box); // one voxel, or a whole tile of interior
        for (auto c = box.begin(); c; ++c) labels.set(grid::Coord((*c).x(), (*c).y(), (*c).z()), options.label);
    }
    return labels;
}

/// Inside = |winding number| > 0.5 at the voxel centre, over every centre in the bounding box. The
/// absolute value accepts surfaces oriented inwards as a whole (winding number -1 inside).
grid::LabelGrid voxelize_winding_number(const TriangleMesh& mesh, double h, const IndexRange& range,
                                        const VoxelizeOptions& options)
{
    const WindingNumber winding(mesh);
    const auto nx = static_cast<std::size_t>(range.dims.x());
    const auto ny = static_cast<std::size_t>(range.dims.y());
    const int nz = range.dims.z();
    std::vector<std::uint8_t> inside(range.voxel_count(), 0);
    const auto slice = [&](int k) {
        for (std::size_t j = 0; j < ny; ++j)
            for (std::size_t i = 0; i < nx; ++i) {
                const Eigen::Vector3d ijk = range.lo.cast<double>() + Eigen::Vector3d(double(i), double(j), double(k));
                inside[i + nx * (j + ny * static_cast<std::size_t>(k))] = std::abs(winding.at(h * ijk)) > 0.5 ? 1 : 0;
            }
    };
    // Slices in parallel, a few per thread at a time; between steps this thread draws the progress.
    Progress progress("voxelizing " + options.name, static_cast<std::uint64_t>(nz));
    const int slices_per_step = 4 * tbb::this_task_arena::max_concurrency();
    for (int k0 = 0; k0 < nz; k0 += slices_per_step) {
        const int k1 = std::min(nz, k0 + slices_per_step);
        tbb::parallel_for(tbb::blocked_range<int>(k0, k1, 1), [&](const tbb::blocked_range<int>& r) {
            for (int k = r.begin(); k < r.end(); ++k) slice(k);
        });
        progress.update(static_cast<std::uint64_t>(k1));
    }
    progress.finish();

    grid::LabelGrid labels(scaling(h));
    for (int k = 0; k < nz; ++k)
        for (std::size_t j = 0; j < ny; ++j)
            for (std::size_t i = 0; i < nx; ++i)
                if (inside[i + nx * (j + ny * static_cast<std::size_t>(k))])
                    labels.set(range.lo + grid::Coord(static_cast<int>(i), static_cast<int>(j), k), options.label);
    return labels;
}

const char* method_name(VoxelizeMethod m)
{
    return m == VoxelizeMethod::level_set ? "OpenVDB mesh-to-volume" : "winding number";
}

} // namespace

grid::LabelGrid voxelize_mesh(const TriangleMesh& mesh_mm, double voxel_mm, const VoxelizeOptions& options)
{
    if (!std::isfinite(voxel_mm) || voxel_mm <= 0.0)
        throw file_error(options.name, fmt::format("voxel size {} mm must be positive and finite", voxel_mm));
    if (voxel_mm < grid::k_min_voxel_mm)
        throw file_error(options.name, fmt::format("voxel size {:g} mm is below the 0.0001 mm (0.1 micrometre) limit (a mesh "
                                                   "this small needs --scale, millimetres per file unit)",
                                                   voxel_mm));
    if (options.label == 0) throw file_error(options.name, "the inside label must be non-zero (0 is background)");
    check_mesh(mesh_mm, options.name);
    const MeshInfo info = mesh_info(mesh_mm);
    const IndexRange range = bbox_index_range(info, voxel_mm, options.name);

    VoxelizeMethod method = options.method;
    if (method == VoxelizeMethod::automatic)
        method = info.closed ? VoxelizeMethod::level_set : VoxelizeMethod::winding_number;
    if (method == VoxelizeMethod::level_set && !info.closed)
        throw file_error(options.name, fmt::format("OpenVDB mesh-to-volume needs a closed mesh, this one has {} "
                                                   "boundary and {} non-manifold edges",
                                                   info.boundary_edges, info.non_manifold_edges));
    if (!info.closed) check_encloses_volume(info, options);
    if (method == VoxelizeMethod::winding_number && !info.consistently_oriented)
        log::warn("{}: neighbouring triangles disagree on which side is outside; the winding number, and "
                  "so the solid, may be wrong near them",
                  options.name);

    grid::LabelGrid labels = method == VoxelizeMethod::level_set
                                 ? voxelize_level_set(mesh_mm, voxel_mm, options)
                                 : voxelize_winding_number(mesh_mm, voxel_mm, range, options);
    const std::uint64_t count = labels.active_voxel_count();
    if (count == 0)
        throw file_error(options.name,
                         fmt::format("no voxel centre is inside the mesh at voxel size {:g} mm ({}; bounding box "
                                     "{:.4g} x {:.4g} x {:.4g} mm): it encloses no volume, or the voxels are too big",
                                     voxel_mm, method_name(method), info.bbox_max.x() - info.bbox_min.x(),
                                     info.bbox_max.y() - info.bbox_min.y(), info.bbox_max.z() - info.bbox_min.z()));
    log::info("{}: {} voxels of {:g} mm inside ({}), {:.4g} mm^3", options.name, count, voxel_mm, method_name(method),
              static_cast<double>(count) * voxel_mm * voxel_mm * voxel_mm);
    return labels;
}

double default_voxel_mm(const MeshInfo& info) { return (info.bbox_max - info.bbox_min).maxCoeff() / 128.0; }

} // namespace vox::io
