#include "io/winding_number.hpp"

#include "io/mesh.hpp"
#include "io/mesh_info.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <random>
#include <thread>
#include <vector>

namespace vox::io {
namespace {

const std::string k_data = VOX_SOURCE_DIR "/data/";
constexpr double k_pi = std::numbers::pi;

/// Hemisphere z >= 0 of radius r about the origin, oriented outwards, open along the equator,
/// which is a regular polygon in the plane z = 0.
TriangleMesh hemisphere(double r, int rings, int segments)
{
    TriangleMesh mesh;
    mesh.vertices.emplace_back(0.0, 0.0, r);
    for (int i = 1; i <= rings; ++i) {
        const double theta = 0.5 * k_pi * i / rings;
        for (int j = 0; j < segments; ++j) {
            const double phi = 2.0 * k_pi * j / segments;
            mesh.vertices.emplace_back(r * std::sin(theta) * std::cos(phi), r * std::sin(theta) * std::sin(phi),
                                       i == rings ? 0.0 : r * std::cos(theta));
        }
    }
    const auto ring = [segments](int i, int j) { return 1 + (i - 1) * segments + (j % segments); };
    for (int j = 0; j < segments; ++j) mesh.triangles.emplace_back(0, ring(1, j), ring(1, j + 1));
    for (int i = 1; i < rings; ++i)
        for (int j = 0; j < segments; ++j) {
            mesh.triangles.emplace_back(ring(i, j), ring(i + 1, j), ring(i + 1, j + 1));
            mesh.triangles.emplace_back(ring(i, j), ring(i + 1, j + 1), ring(i, j + 1));
        }
    return mesh;
}

Eigen::Vector3d random_point(std::mt19937& rng, const Eigen::Vector3d& lo, const Eigen::Vector3d& hi)
{
    std::uniform_real_distribution<double> u(0.0, 1.0);
    return lo + Eigen::Vector3d(u(rng), u(rng), u(rng)).cwiseProduct(hi - lo);
}

TEST(WindingNumber, SolidAngleOfAnOctant)
{
    // The triangle through the three unit axis points covers one octant seen from the origin.
    const Eigen::Vector3d x(1, 0, 0), y(0, 1, 0), z(0, 0, 1), o(0, 0, 0);
    EXPECT_NEAR(triangle_solid_angle(x, y, z, o), 4.0 * k_pi / 8.0, 1e-15);
    EXPECT_NEAR(triangle_solid_angle(x, z, y, o), -4.0 * k_pi / 8.0, 1e-15);
    // Seen from within its plane (outside the triangle) it subtends nothing.
    EXPECT_NEAR(triangle_solid_angle(x, y, z, Eigen::Vector3d(2, -1, 0)), 0.0, 1e-15);
    // Seen from just behind its centre it covers almost half the sphere.
    const Eigen::Vector3d behind = (x + y + z) / 3.0 - 1e-9 * Eigen::Vector3d::Ones();
    EXPECT_NEAR(triangle_solid_angle(x, y, z, behind), 2.0 * k_pi, 1e-6);
}

TEST(WindingNumber, ClosedSphereIsOneInsideZeroOutside)
{
    const TriangleMesh sphere = read_mesh(k_data + "sphere.off");
    const MeshInfo info = mesh_info(sphere);
    const Eigen::Vector3d centre = 0.5 * (info.bbox_min + info.bbox_max);
    const double r = 0.5 * (info.bbox_max - info.bbox_min).maxCoeff();
    const WindingNumber fast(sphere);
    std::mt19937 rng(1);
    for (int n = 0; n < 500; ++n) {
        const Eigen::Vector3d p =
            random_point(rng, centre - Eigen::Vector3d::Constant(3 * r), centre + Eigen::Vector3d::Constant(3 * r));
        const double distance = (p - centre).norm();
        // The faces of this icosphere stay beyond 0.9 r from its centre, its vertices are at r.
        if (distance > 0.9 * r && distance < 1.1 * r) continue;
        const double expected = distance < r ? 1.0 : 0.0;
        EXPECT_NEAR(winding_number_exact(sphere, p), expected, 1e-12);
        EXPECT_NEAR(fast.at(p), expected, 5e-3);
    }
    // Turned inside out it counts -1.
    TriangleMesh flipped = sphere;
    for (Eigen::Vector3i& t : flipped.triangles) std::swap(t[1], t[2]);
    EXPECT_NEAR(winding_number_exact(flipped, centre), -1.0, 1e-12);
    EXPECT_NEAR(WindingNumber(flipped).at(centre), -1.0, 5e-3);
}

TEST(WindingNumber, OpenHemisphereIsHalfAtItsCentre)
{
    // The solid angle of an open surface depends only on its boundary; this one's boundary is a
    // polygon through whose plane the centre is, so the surface covers exactly half the sphere.
    const TriangleMesh dome = hemisphere(2.0, 12, 32);
    EXPECT_FALSE(mesh_info(dome).closed);
    const WindingNumber fast(dome);
    EXPECT_NEAR(winding_number_exact(dome, Eigen::Vector3d::Zero()), 0.5, 1e-12);
    EXPECT_NEAR(fast.at(Eigen::Vector3d::Zero()), 0.5, 5e-3);
    EXPECT_GT(fast.at(Eigen::Vector3d(0, 0, 1.0)), 0.5);  // under the dome
    EXPECT_LT(fast.at(Eigen::Vector3d(0, 0, -1.0)), 0.5); // below its rim
    // Crossing the surface outwards lowers the winding number by exactly 1.
    const Eigen::Vector3d a = dome.vertices[dome.triangles[40][0]];
    const Eigen::Vector3d b = dome.vertices[dome.triangles[40][1]];
    const Eigen::Vector3d c = dome.vertices[dome.triangles[40][2]];
    const Eigen::Vector3d centroid = (a + b + c) / 3.0;
    const Eigen::Vector3d normal = (b - a).cross(c - a).normalized();
    EXPECT_NEAR(fast.at(centroid - 1e-7 * normal) - fast.at(centroid + 1e-7 * normal), 1.0, 1e-5);
}

struct Errors {
    double max = 0.0;
    double mean = 0.0;
};

/// |fast - exact| over random points in the mesh's bounding box grown by 20% per side.
Errors fast_errors(const TriangleMesh& mesh, double beta, int samples)
{
    const MeshInfo info = mesh_info(mesh);
    const Eigen::Vector3d margin = 0.2 * (info.bbox_max - info.bbox_min);
    const WindingNumber fast(mesh, beta);
    std::mt19937 rng(7);
    Errors errors;
    for (int n = 0; n < samples; ++n) {
        const Eigen::Vector3d p = random_point(rng, info.bbox_min - margin, info.bbox_max + margin);
        const double error = std::abs(fast.at(p) - winding_number_exact(mesh, p));
        errors.max = std::max(errors.max, error);
        errors.mean += error / samples;
    }
    return errors;
}

TEST(WindingNumber, FastAgreesWithExact)
{
    // The truncated expansion errs ~(1/beta)^3 relative to a far cluster's contribution.
    for (const char* file : {"elephant.off", "lion.off", "cylinder.off"}) {
        SCOPED_TRACE(file);
        const TriangleMesh mesh = read_mesh(k_data + file);
        const Errors default_beta = fast_errors(mesh, 2.0, 400);
        EXPECT_LT(default_beta.max, 5e-3);
        EXPECT_LT(default_beta.mean, 1e-3);
        const Errors wider = fast_errors(mesh, 3.0, 400);
        EXPECT_LT(wider.max, 1e-3);
        EXPECT_LT(wider.mean, 0.3 * default_beta.mean);
    }
}

TEST(WindingNumber, ConcurrentQueriesAgree)
{
    const TriangleMesh lion = read_mesh(k_data + "lion.off");
    const MeshInfo info = mesh_info(lion);
    const WindingNumber fast(lion);
    std::mt19937 rng(3);
    std::vector<Eigen::Vector3d> points;
    for (int n = 0; n < 2000; ++n) points.push_back(random_point(rng, info.bbox_min, info.bbox_max));
    std::vector<double> serial;
    for (const Eigen::Vector3d& p : points) serial.push_back(fast.at(p));

    std::vector<std::vector<double>> parallel(4, std::vector<double>(points.size()));
    std::vector<std::thread> threads;
    for (auto& out : parallel)
        threads.emplace_back([&fast, &points, &out] {
            for (std::size_t i = 0; i < points.size(); ++i) out[i] = fast.at(points[i]);
        });
    for (std::thread& t : threads) t.join();
    for (const auto& out : parallel) EXPECT_EQ(out, serial);
}

TEST(WindingNumber, EmptyMeshIsZero) { EXPECT_EQ(WindingNumber(TriangleMesh{}).at(Eigen::Vector3d::Zero()), 0.0); }

} // namespace
} // namespace vox::io
