#include "io/mesh_voxelizer.hpp"

#include "core/error.hpp"
#include "core/log.hpp"
#include "core/memory_limit.hpp"
#include "io/mesh.hpp"
#include "io/mesh_info.hpp"

#include <Eigen/Geometry>
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <map>
#include <set>
#include <string>
#include <vector>

namespace vox::io {
namespace {

const std::string k_data = VOX_SOURCE_DIR "/data/";

/// The voxelizer reports each solid at info level; tests keep the log quiet.
class Voxelize : public ::testing::Test {
protected:
    void SetUp() override { log::set_verbosity(log::Verbosity::quiet); }
    void TearDown() override { log::set_verbosity(m_saved); }

private:
    log::Verbosity m_saved = log::verbosity();
};

/// The axis-aligned box [lo, hi] as 12 outward triangles.
TriangleMesh box_mesh(const Eigen::Vector3d& lo, const Eigen::Vector3d& hi)
{
    TriangleMesh mesh;
    for (int i = 0; i < 8; ++i)
        mesh.vertices.emplace_back(i & 1 ? hi.x() : lo.x(), i & 2 ? hi.y() : lo.y(), i & 4 ? hi.z() : lo.z());
    const int quads[6][4] = {{0, 2, 3, 1}, {4, 5, 7, 6}, {0, 1, 5, 4}, {2, 6, 7, 3}, {0, 4, 6, 2}, {1, 3, 7, 5}};
    for (const auto& q : quads) {
        mesh.triangles.emplace_back(q[0], q[1], q[2]);
        mesh.triangles.emplace_back(q[0], q[2], q[3]);
    }
    return mesh;
}

double voxel_volume(const grid::LabelGrid& labels)
{
    const double h = labels.voxel_size().x();
    return static_cast<double>(labels.active_voxel_count()) * h * h * h;
}

/// Tolerance on |voxel volume - mesh volume| when voxels are classified by their centres. Only
/// the ~sqrt(3) A / h^2 voxels the surface crosses can be wrong, each by an error within
/// +-h^3 / 2 whose mean is ~0 on a surface curved at scales above h; taken as independent and
/// uniform (standard deviation h^3 / sqrt(12) each), six standard deviations of their sum.
double sampling_tolerance(const MeshInfo& info, double h)
{
    const double crossed = std::sqrt(3.0) * info.area_mm2 / (h * h);
    return 6.0 * h * h * h * std::sqrt(crossed / 12.0);
}

/// The mesh with each boundary loop closed by a fan to the loop's centroid, and an upper bound on
/// the volume between these caps and any other caps spanning the same loops: sum over loops of
/// cap area times the loop's largest distance from its best plane. Needs a consistently oriented
/// mesh whose boundary vertices each start one boundary edge.
struct Capped {
    TriangleMesh mesh;
    double slack_mm3 = 0.0;
};

Capped cap_holes(const TriangleMesh& open)
{
    std::set<std::pair<int, int>> directed;
    for (const Eigen::Vector3i& t : open.triangles)
        for (int c = 0; c < 3; ++c) directed.emplace(t[c], t[(c + 1) % 3]);
    std::map<int, int> next; // boundary edges: used one way only
    for (const auto& [a, b] : directed)
        if (!directed.contains({b, a})) next[a] = b;

    Capped capped{open, 0.0};
    std::set<int> done;
    for (const auto& [start, unused] : next) {
        if (done.contains(start)) continue;
        std::vector<int> loop;
        for (int v = start; loop.empty() || v != start; v = next.at(v)) {
            loop.push_back(v);
            done.insert(v);
        }
        Eigen::Vector3d centroid = Eigen::Vector3d::Zero();
        Eigen::Vector3d vector_area = Eigen::Vector3d::Zero();
        for (std::size_t i = 0; i < loop.size(); ++i) {
            centroid += open.vertices[loop[i]] / double(loop.size());
            vector_area += 0.5 * open.vertices[loop[i]].cross(open.vertices[loop[(i + 1) % loop.size()]]);
        }
        double off_plane = 0.0;
        for (const int v : loop)
            off_plane = std::max(off_plane, std::abs((open.vertices[v] - centroid).dot(vector_area.normalized())));
        capped.slack_mm3 += vector_area.norm() * off_plane;
        const int apex = static_cast<int>(capped.mesh.vertices.size());
        capped.mesh.vertices.push_back(centroid);
        for (std::size_t i = 0; i < loop.size(); ++i) // walked against the mesh: consistent orientation
            capped.mesh.triangles.emplace_back(loop[(i + 1) % loop.size()], loop[i], apex);
    }
    return capped;
}

/// Voxels labelled in exactly one of the two grids.
std::uint64_t symmetric_difference(const grid::LabelGrid& a, const grid::LabelGrid& b)
{
    std::uint64_t only = 0;
    a.for_each_active([&](const grid::Coord& c, std::int32_t) { only += b.get(c) == 0 ? 1 : 0; });
    b.for_each_active([&](const grid::Coord& c, std::int32_t) { only += a.get(c) == 0 ? 1 : 0; });
    return only;
}

VoxelizeOptions with_method(VoxelizeMethod method)
{
    VoxelizeOptions options;
    options.method = method;
    return options;
}

TEST_F(Voxelize, BoxGivesExactCountAndIndexBounds)
{
    // Voxel centres (i, j, k) * 0.5 inside [-1.3, 2.6] x [0.2, 3.7] x [-0.9, 1.2]: i in -2..5,
    // j in 1..7, k in -1..2, each at least 0.1 mm from a face.
    const TriangleMesh box = box_mesh({-1.3, 0.2, -0.9}, {2.6, 3.7, 1.2});
    for (const VoxelizeMethod method : {VoxelizeMethod::level_set, VoxelizeMethod::winding_number}) {
        SCOPED_TRACE(static_cast<int>(method));
        const grid::LabelGrid labels = voxelize_mesh(box, 0.5, with_method(method));
        EXPECT_EQ(labels.active_voxel_count(), 8u * 7u * 4u);
        const grid::IndexBox bounds = labels.index_bounds();
        EXPECT_EQ(bounds.min, grid::Coord(-2, 1, -1));
        EXPECT_EQ(bounds.max, grid::Coord(5, 7, 2));
        EXPECT_EQ(labels.label_histogram().begin()->first, 1);
        EXPECT_TRUE(labels.index_to_world().isApprox(Eigen::Vector4d(0.5, 0.5, 0.5, 1.0).asDiagonal().toDenseMatrix()));
    }
}

TEST_F(Voxelize, SphereVolumeConvergesToMeshVolume)
{
    const TriangleMesh sphere = read_mesh(k_data + "sphere.off");
    const MeshInfo info = mesh_info(sphere);
    const double diameter = (info.bbox_max - info.bbox_min).maxCoeff();
    double previous_error = std::numeric_limits<double>::infinity();
    for (const double h : {diameter / 16.0, diameter / 64.0}) {
        SCOPED_TRACE(h);
        const double error = std::abs(voxel_volume(voxelize_mesh(sphere, h)) - info.enclosed_volume_mm3);
        EXPECT_LT(error, sampling_tolerance(info, h));
        EXPECT_LT(error, 0.25 * previous_error);
        previous_error = error;
    }
}

TEST_F(Voxelize, ElephantVolumeMatchesMeshVolume)
{
    const TriangleMesh elephant = read_mesh(k_data + "elephant.off");
    const MeshInfo info = mesh_info(elephant);
    const double h = default_voxel_mm(info);
    EXPECT_DOUBLE_EQ(h, (info.bbox_max - info.bbox_min).maxCoeff() / 128.0);
    for (const VoxelizeMethod method : {VoxelizeMethod::level_set, VoxelizeMethod::winding_number}) {
        SCOPED_TRACE(static_cast<int>(method));
        const grid::LabelGrid labels = voxelize_mesh(elephant, h, with_method(method));
        EXPECT_LT(std::abs(voxel_volume(labels) - info.enclosed_volume_mm3), sampling_tolerance(info, h));
    }
}

TEST_F(Voxelize, WindingNumberAndLevelSetAgreeOnClosedMeshes)
{
    for (const auto& [file, divisions] : {std::pair{"sphere.off", 64.0}, std::pair{"elephant.off", 128.0}}) {
        SCOPED_TRACE(file);
        const TriangleMesh mesh = read_mesh(k_data + file);
        const MeshInfo info = mesh_info(mesh);
        const double h = (info.bbox_max - info.bbox_min).maxCoeff() / divisions;
        const grid::LabelGrid level_set = voxelize_mesh(mesh, h, with_method(VoxelizeMethod::level_set));
        const grid::LabelGrid winding = voxelize_mesh(mesh, h, with_method(VoxelizeMethod::winding_number));
        // The winding number is exact here (0 or 1 away from the surface). OpenVDB decides signs by
        // flood-filling voxels the surface does not cross, which errs in parts thinner than a voxel
        // (the elephant's: 1.3% of the layer of voxels along its surface, both ways).
        const double surface_layer = info.area_mm2 / (h * h);
        EXPECT_LT(static_cast<double>(symmetric_difference(level_set, winding)), 0.05 * surface_layer);
    }
}

TEST_F(Voxelize, LionScanWithHolesGivesTheCappedSolid)
{
    const TriangleMesh lion = read_mesh(k_data + "lion.off");
    const MeshInfo info = mesh_info(lion);
    ASSERT_FALSE(info.closed);
    ASSERT_TRUE(info.consistently_oriented);
    const Capped capped = cap_holes(lion);
    const MeshInfo capped_info = mesh_info(capped.mesh);
    ASSERT_TRUE(capped_info.closed);
    // Across a hole, the winding number's 0.5 level spans the hole like a soap film; the fan cap
    // spans it too, within the slab the loop's vertices leave around their plane.
    const double h = default_voxel_mm(info);
    const grid::LabelGrid labels = voxelize_mesh(lion, h);
    EXPECT_LT(std::abs(voxel_volume(labels) - capped_info.enclosed_volume_mm3),
              sampling_tolerance(capped_info, h) + capped.slack_mm3);
}

TEST_F(Voxelize, OpenBoxIsFilledOpenTubeIsRefused)
{
    // A box missing one face is like a scan with a hole (cap 1/5 of the area). Inside it the
    // winding number is 1 - (solid angle of the hole) / 4 pi, and a planar hole subtends less than
    // a hemisphere from any point off its plane: all 7^3 centres of the closed box are inside.
    TriangleMesh box = box_mesh(Eigen::Vector3d::Constant(-0.95), Eigen::Vector3d::Constant(0.95));
    box.triangles.erase(box.triangles.begin() + 2, box.triangles.begin() + 4); // the face z = +0.95
    const grid::LabelGrid labels = voxelize_mesh(box, 0.25);
    EXPECT_EQ(labels.active_voxel_count(), 7u * 7u * 7u);
    // Oriented inwards as a whole it is the same solid.
    TriangleMesh inverted = box;
    for (Eigen::Vector3i& t : inverted.triangles) std::swap(t[1], t[2]);
    EXPECT_EQ(voxelize_mesh(inverted, 0.25).active_voxel_count(), labels.active_voxel_count());
    // Missing two opposite faces it is a tube: caps 2/4 of its area.
    box.triangles.erase(box.triangles.begin(), box.triangles.begin() + 2); // the face z = -0.95
    EXPECT_THROW((void)voxelize_mesh(box, 0.25), InputError);
}

TEST_F(Voxelize, HalfPipeIsRefusedWithTheNumbers)
{
    const std::string path = k_data + "cylinder.off";
    VoxelizeOptions options;
    options.name = path;
    try {
        (void)voxelize_mesh(read_mesh(path), 0.05, options);
        ADD_FAILURE() << "no error";
    } catch (const InputError& e) {
        const std::string message = e.what();
        EXPECT_EQ(message.rfind(path + ": the mesh is open and encloses no volume", 0), 0u) << message;
        EXPECT_NE(message.find("136 boundary edges"), std::string::npos) << message;
    }
}

TEST_F(Voxelize, BadParametersRefused)
{
    const TriangleMesh box = box_mesh({0, 0, 0}, {1, 1, 1});
    for (const double h :
         {0.0, -0.1, std::numeric_limits<double>::quiet_NaN(), std::numeric_limits<double>::infinity()})
        EXPECT_THROW((void)voxelize_mesh(box, h), InputError);
    // A box between voxel centres: nothing is inside.
    EXPECT_THROW((void)voxelize_mesh(box_mesh({0.1, 0.1, 0.1}, {0.2, 0.2, 0.2}), 1.0), InputError);
    // The OpenVDB path needs a closed mesh.
    TriangleMesh open = box;
    open.triangles.pop_back();
    EXPECT_THROW((void)voxelize_mesh(open, 0.1, with_method(VoxelizeMethod::level_set)), InputError);
}

TEST_F(Voxelize, MemoryLimitCheckedBeforeAllocating)
{
    const std::uint64_t saved = memory_limit_bytes();
    set_memory_limit_bytes(std::uint64_t{1} << 20);
    const TriangleMesh box = box_mesh({0, 0, 0}, {1000, 1000, 1000});
    EXPECT_THROW((void)voxelize_mesh(box, 1.0), InputError);  // 1e9 voxels, 4 GB
    EXPECT_THROW((void)voxelize_mesh(box, 1e-6), InputError); // beyond 64-bit sizes
    set_memory_limit_bytes(saved);
}

} // namespace
} // namespace vox::io
