#include "io/mesh_info.hpp"

#include "io/mesh.hpp"

#include <Eigen/Geometry>
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstddef>
#include <numbers>
#include <string>
#include <utility>

namespace vox::io {
namespace {

const std::string k_data = VOX_SOURCE_DIR "/data/";

/// The unit cube [0,1]^3 oriented outwards, each face split into two triangles, the face z = 0
/// first. Corner i has coordinates (i & 1, i >> 1 & 1, i >> 2 & 1).
TriangleMesh unit_cube()
{
    constexpr std::array<std::array<int, 4>, 6> quads{
        {{0, 2, 3, 1}, {4, 5, 7, 6}, {0, 1, 5, 4}, {2, 6, 7, 3}, {0, 4, 6, 2}, {1, 3, 7, 5}}};
    TriangleMesh cube;
    for (int i = 0; i < 8; ++i) cube.vertices.emplace_back(double(i & 1), double(i >> 1 & 1), double(i >> 2 & 1));
    for (const auto& q : quads) {
        cube.triangles.emplace_back(q[0], q[1], q[2]);
        cube.triangles.emplace_back(q[0], q[2], q[3]);
    }
    return cube;
}

TEST(MeshInfo, TetrahedronVolumeAndAreaExact)
{
    TriangleMesh tet;
    tet.vertices = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
    tet.triangles = {{0, 2, 1}, {0, 1, 3}, {0, 3, 2}, {1, 2, 3}};
    MeshInfo info = mesh_info(tet);
    EXPECT_TRUE(info.closed);
    EXPECT_TRUE(info.consistently_oriented);
    EXPECT_EQ(info.edges, 6u);
    EXPECT_NEAR(info.enclosed_volume_mm3, 1.0 / 6.0, 1e-15);
    EXPECT_NEAR(info.area_mm2, 1.5 + std::sqrt(3.0) / 2.0, 1e-15);

    // The volume of a closed surface does not depend on where it is.
    for (Eigen::Vector3d& p : tet.vertices) p += Eigen::Vector3d(1000.0, -2000.0, 500.0);
    EXPECT_NEAR(mesh_info(tet).enclosed_volume_mm3, 1.0 / 6.0, 1e-12);

    // Inward orientation negates it.
    for (Eigen::Vector3i& t : tet.triangles) std::swap(t[1], t[2]);
    info = mesh_info(tet);
    EXPECT_NEAR(info.enclosed_volume_mm3, -1.0 / 6.0, 1e-12);
    EXPECT_TRUE(info.consistently_oriented);
}

TEST(MeshInfo, OpenBoxHoleCapIsTheMissingFace)
{
    TriangleMesh box = unit_cube();
    box.triangles.erase(box.triangles.begin(), box.triangles.begin() + 2); // the face z = 0
    const MeshInfo info = mesh_info(box);
    EXPECT_FALSE(info.closed);
    EXPECT_EQ(info.boundary_edges, 4u);
    EXPECT_EQ(info.boundary_loops, 1u);
    EXPECT_NEAR(info.area_mm2, 5.0, 1e-12);
    EXPECT_NEAR(info.boundary_cap_area_mm2, 1.0, 1e-12);
    EXPECT_TRUE(info.consistently_oriented);
}

TEST(MeshInfo, SampleMeshes)
{
    struct Expected {
        const char* file;
        std::size_t vertices, triangles;
        bool closed;
    };
    for (const Expected& e : {Expected{"elephant.off", 2775, 5558, true}, Expected{"lion.off", 7529, 14859, false},
                              Expected{"sphere.off", 162, 320, true}, Expected{"cylinder.off", 1200, 2262, false}}) {
        SCOPED_TRACE(e.file);
        const MeshInfo info = mesh_info(read_mesh(k_data + e.file));
        EXPECT_EQ(info.vertices, e.vertices);
        EXPECT_EQ(info.triangles, e.triangles);
        EXPECT_EQ(info.closed, e.closed);
        // Every triangle has 3 edge uses: interior edges take 2, boundary edges 1.
        if (info.non_manifold_edges == 0) {
            EXPECT_EQ(3 * info.triangles, 2 * info.edges - info.boundary_edges);
        }
        if (e.closed) {
            EXPECT_GT(info.enclosed_volume_mm3, 0.0);
            EXPECT_TRUE(info.consistently_oriented);
        }
    }
    // A half-pipe of radius 1 mm and length 3 mm: area 3 pi; its one boundary loop projects onto the
    // 2 x 3 rectangle of the pipe's diametral plane, so the loop's vector area is exactly 6.
    const MeshInfo cylinder = mesh_info(read_mesh(k_data + "cylinder.off"));
    EXPECT_EQ(cylinder.boundary_edges, 136u);
    EXPECT_EQ(cylinder.boundary_loops, 1u);
    EXPECT_NEAR(cylinder.area_mm2, 3.0 * std::numbers::pi, 1e-3 * 3.0 * std::numbers::pi);
    EXPECT_NEAR(cylinder.boundary_cap_area_mm2, 6.0, 1e-9);
    const MeshInfo lion = mesh_info(read_mesh(k_data + "lion.off"));
    EXPECT_EQ(lion.boundary_edges, 205u);
    EXPECT_EQ(lion.non_manifold_edges, 0u);
    EXPECT_EQ(lion.boundary_loops, 5u);
    // Euler characteristic V - E + F = 2 of a closed genus-0 surface.
    const MeshInfo sphere = mesh_info(read_mesh(k_data + "sphere.off"));
    EXPECT_EQ(
        static_cast<long>(sphere.vertices) - static_cast<long>(sphere.edges) + static_cast<long>(sphere.triangles), 2);
}

TEST(MeshInfo, SphereVolumeBetweenInscribedBounds)
{
    // sphere.off's vertices lie on a sphere (to the file's 5 digits), so its volume is below that
    // of the sphere through its farthest vertex and above that of the sphere touching its nearest
    // face plane.
    const TriangleMesh mesh = read_mesh(k_data + "sphere.off");
    const MeshInfo info = mesh_info(mesh);
    const Eigen::Vector3d centre = 0.5 * (info.bbox_min + info.bbox_max);
    double outer = 0.0;
    for (const Eigen::Vector3d& p : mesh.vertices) outer = std::max(outer, (p - centre).norm());
    double inner = outer;
    for (const Eigen::Vector3d& p : mesh.vertices) EXPECT_NEAR((p - centre).norm(), outer, 1e-4 * outer);
    for (const Eigen::Vector3i& t : mesh.triangles) {
        const Eigen::Vector3d a = mesh.vertices[t[0]];
        const Eigen::Vector3d n = (mesh.vertices[t[1]] - a).cross(mesh.vertices[t[2]] - a).normalized();
        inner = std::min(inner, std::abs((a - centre).dot(n)));
    }
    const auto ball = [](double r) { return 4.0 / 3.0 * std::numbers::pi * r * r * r; };
    EXPECT_LT(info.enclosed_volume_mm3, ball(outer));
    EXPECT_GT(info.enclosed_volume_mm3, ball(inner));
}

} // namespace
} // namespace vox::io
