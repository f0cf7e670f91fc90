#include "io/mesh.hpp"

#include "core/error.hpp"
#include "io/mesh_info.hpp"
#include "test_support.hpp"

#include <gtest/gtest.h>

#include <array>
#include <cstdint>
#include <filesystem>
#include <limits>
#include <map>
#include <sstream>
#include <string>
#include <vector>

namespace vox::io {
namespace {

const std::string k_bad = VOX_TEST_DATA_DIR "/bad/";

// The unit cube [0,1]^3, oriented outwards: corner i has coordinates (i & 1, i >> 1 & 1, i >> 2 & 1).
const char* const k_cube_corners = "0 0 0\n1 0 0\n0 1 0\n1 1 0\n0 0 1\n1 0 1\n0 1 1\n1 1 1\n";
const int k_cube_quads[6][4] = {{0, 2, 3, 1}, {4, 5, 7, 6}, {0, 1, 5, 4}, {2, 6, 7, 3}, {0, 4, 6, 2}, {1, 3, 7, 5}};

std::string cube_quads_text()
{
    std::ostringstream s;
    for (const auto& q : k_cube_quads) s << "4 " << q[0] << ' ' << q[1] << ' ' << q[2] << ' ' << q[3] << '\n';
    return s.str();
}

std::string cube_off() { return "OFF\n# unit cube\n8 6 12\n" + std::string(k_cube_corners) + cube_quads_text(); }

/// OBJ with 1-based "v/vt/vn" corners; `flip_last` reverses the last quad (an orientation defect).
std::string cube_obj(bool flip_last = false)
{
    std::ostringstream s;
    for (int i = 0; i < 8; ++i) s << "v " << (i & 1) << ' ' << (i >> 1 & 1) << ' ' << (i >> 2 & 1) << '\n';
    s << "vt 0 0\nvn 0 0 1\n";
    for (int f = 0; f < 6; ++f) {
        s << 'f';
        for (int c = 0; c < 4; ++c)
            s << ' ' << 1 + (flip_last && f == 5 ? k_cube_quads[f][3 - c] : k_cube_quads[f][c]) << "/1/1";
        s << '\n';
    }
    return s.str();
}

std::string cube_ply()
{
    return "ply\nformat ascii 1.0\nelement vertex 8\nproperty float x\nproperty float y\nproperty float z\n"
           "element face 6\nproperty list uchar int vertex_indices\nend_header\n" +
           std::string(k_cube_corners) + cube_quads_text();
}

Eigen::Vector3d cube_corner(int i) { return {double(i & 1), double(i >> 1 & 1), double(i >> 2 & 1)}; }

std::string cube_stl_ascii()
{
    std::ostringstream s;
    s << "solid cube\n";
    for (const auto& q : k_cube_quads)
        for (const auto& t : {std::array{q[0], q[1], q[2]}, std::array{q[0], q[2], q[3]}}) {
            s << "facet normal 0 0 0\n outer loop\n";
            for (int c : t) s << "  vertex " << cube_corner(c).transpose() << '\n';
            s << " endloop\nendfacet\n";
        }
    s << "endsolid cube\n";
    return s.str();
}

std::string cube_stl_binary()
{
    // The header starts with "solid" on purpose: binary files written by some CAD tools do.
    std::string s = "solid but binary";
    s.resize(80, ' ');
    const auto put = [&s](const void* p, std::size_t n) { s.append(static_cast<const char*>(p), n); };
    const std::uint32_t count = 12;
    put(&count, 4);
    for (const auto& q : k_cube_quads)
        for (const auto& t : {std::array{q[0], q[1], q[2]}, std::array{q[0], q[2], q[3]}}) {
            const float normal[3] = {0, 0, 0};
            put(normal, 12);
            for (int c : t) {
                const Eigen::Vector3f p = cube_corner(c).cast<float>();
                put(p.data(), 12);
            }
            const std::uint16_t attribute = 0;
            put(&attribute, 2);
        }
    return s;
}

void expect_unit_cube(const TriangleMesh& mesh, double scale)
{
    const MeshInfo info = mesh_info(mesh);
    EXPECT_EQ(info.vertices, 8u);
    EXPECT_EQ(info.triangles, 12u);
    EXPECT_EQ(info.edges, 18u); // 12 cube edges + 6 face diagonals
    EXPECT_EQ(info.boundary_edges, 0u);
    EXPECT_EQ(info.non_manifold_edges, 0u);
    EXPECT_TRUE(info.closed);
    EXPECT_TRUE(info.consistently_oriented);
    EXPECT_NEAR(info.area_mm2, 6.0 * scale * scale, 1e-12);
    EXPECT_NEAR(info.enclosed_volume_mm3, scale * scale * scale, 1e-12);
    EXPECT_EQ(info.bbox_min, Eigen::Vector3d::Zero());
    EXPECT_EQ(info.bbox_max, Eigen::Vector3d::Constant(scale));
}

TEST(MeshRead, UnitCubeInEveryFormat)
{
    const test::ScratchDir dir;
    for (const auto& [name, bytes] :
         std::vector<std::pair<std::string, std::string>>{{"cube.off", cube_off()},
                                                          {"cube.OBJ", cube_obj()},
                                                          {"cube.ply", cube_ply()},
                                                          {"cube_ascii.stl", cube_stl_ascii()},
                                                          {"cube_binary.stl", cube_stl_binary()}}) {
        SCOPED_TRACE(name);
        const std::string path = dir.write(name, bytes);
        expect_unit_cube(read_mesh(path), 1.0);
        expect_unit_cube(read_mesh(path, 2.5), 2.5); // file units -> mm
    }
}

TEST(MeshRead, FlippedFaceKeepsTheFilesConnectivity)
{
    // A flipped quad: the face stays on the file's vertices (OpenMesh, which read OBJ before, gave
    // such faces fresh vertex copies), so the surface is closed but not consistently oriented.
    const test::ScratchDir dir;
    const TriangleMesh mesh = read_mesh(dir.write("flipped.obj", cube_obj(true)));
    const MeshInfo info = mesh_info(mesh);
    EXPECT_EQ(info.vertices, 8u);
    EXPECT_EQ(info.triangles, 12u);
    EXPECT_TRUE(info.closed);
    EXPECT_FALSE(info.consistently_oriented);
}

TEST(MeshRead, NonManifoldEdgeKept)
{
    const test::ScratchDir dir;
    // Three triangles on the edge 0-1, as scans sometimes have: kept, and counted.
    const std::string off = "OFF\n5 3 0\n0 0 0\n1 0 0\n0 1 0\n0 -1 0\n0 0 1\n3 0 1 2\n3 1 0 3\n3 0 1 4\n";
    const MeshInfo info = mesh_info(read_mesh(dir.write("fin.off", off)));
    EXPECT_EQ(info.triangles, 3u);
    EXPECT_EQ(info.non_manifold_edges, 1u);
    EXPECT_EQ(info.boundary_edges, 6u);
    EXPECT_FALSE(info.closed);
    EXPECT_FALSE(info.consistently_oriented);
}

TEST(MeshRead, DegenerateFacesSkipped)
{
    const test::ScratchDir dir;
    const std::string off = "OFF\n3 2 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n3 0 1 1\n";
    EXPECT_EQ(read_mesh(dir.write("degenerate.off", off)).triangles.size(), 1u);
}

/// Expects read_mesh(path) to throw an InputError of one line "PATH: ..." containing `what`.
void expect_input_error(const std::string& path, const std::string& what, double mm_per_unit = 1.0)
{
    SCOPED_TRACE(path);
    try {
        (void)read_mesh(path, mm_per_unit);
        ADD_FAILURE() << "no error";
    } catch (const InputError& e) {
        const std::string message = e.what();
        EXPECT_EQ(message.rfind(path + ": ", 0), 0u) << message;
        EXPECT_NE(message.find(what), std::string::npos) << message;
        EXPECT_EQ(message.find('\n'), std::string::npos) << message;
    }
}

TEST(MeshRead, MalformedFilesThrowNamingTheFile)
{
    // What each mesh file of the corpus must be refused for (tests/data/bad/README.md says why).
    const std::map<std::string, std::string> expected = {
        {"obj_bad_index.obj", "line 4: face references vertex 7, but the file has only 3 vertices"},
        {"obj_empty.obj", ": is empty"},
        {"obj_huge_polygon.obj", "line 21: a face of 3000 corners, more than the 256 a face may have"},
        {"obj_inf_vertex.obj", "line 4: vertex 4 has a non-finite coordinate (0, 0, inf)"},
        {"obj_nan_vertex.obj", "line 3: vertex 2 has a non-finite coordinate (nan, 10, 0)"},
        {"obj_no_faces.obj", "has no faces"},
        {"obj_short_face.obj", "line 5: a face needs at least 3 vertices, this one has 2"},
        {"obj_zero_index.obj", "line 4: face references vertex 0; OBJ vertex indices start at 1"},
        {"off_bad_index.off", "line 8: face 1 references vertex 99, but there are only 4 vertices"},
        {"off_empty.off", ": is empty"},
        {"off_nan_vertex.off", "vertex 2 has a non-finite coordinate (nan, 1, 0)"},
        {"off_no_faces.off", "has no faces"},
        {"off_not_a_number.off", "line 4: vertex 1: 'zero' is not a number"},
        {"off_truncated.off", "truncated"},
        {"off_wrong_magic.off", "not an OFF file"},
        {"ply_bad_index.ply", "line 17: face 2 references vertex 9, but there are only 4 vertices"},
        {"ply_empty.ply", ": is empty"},
        {"ply_nan_vertex.ply", "vertex 1 has a non-finite coordinate (nan, 0, 0)"},
        {"ply_no_faces.ply", "has no faces ('element face 0'"},
        {"ply_truncated.ply", "truncated: the data ends in vertex 2 of the 3 the header declares"},
        {"ply_truncated_binary.ply", "truncated: the data ends in face 0 of the 1 the header declares"},
        {"ply_wrong_magic.ply", "not a PLY file"},
        {"stl_empty.stl", ": is empty"},
        {"stl_nan_vertex.stl", "triangle 1, corner 1 has a non-finite coordinate"},
        {"stl_truncated.stl", "declares 10 triangles (584 bytes) but has 134 bytes"},
        {"stl_truncated_ascii.stl", "truncated: facet 0 has no 'endloop'"},
    };
    std::size_t seen = 0;
    for (const auto& entry : std::filesystem::directory_iterator(k_bad)) {
        const std::string name = entry.path().filename().string();
        const std::string prefix = name.substr(0, name.find('_') + 1);
        if (prefix != "obj_" && prefix != "off_" && prefix != "ply_" && prefix != "stl_") continue;
        ++seen;
        const auto it = expected.find(name);
        if (it == expected.end()) {
            ADD_FAILURE() << "add " << name << " to this table and to tests/data/bad/README.md";
            continue;
        }
        expect_input_error(k_bad + name, it->second);
    }
    EXPECT_EQ(seen, expected.size()) << "a file listed here is missing from " << k_bad;
}

TEST(MeshRead, BadPathsAndParameters)
{
    expect_input_error(k_bad + "no_such_mesh.off", "no such file");
    expect_input_error(k_bad + "no_such_mesh.obj", "no such file");
    expect_input_error(k_bad + "no_such_mesh.ply", "no such file");
    const test::ScratchDir dir;
    for (const char* name : {"folder.off", "folder.obj", "folder.ply", "folder.stl"}) {
        const std::string folder = dir.path(name);
        std::filesystem::create_directory(folder);
        expect_input_error(folder, "is a folder, not a file");
        expect_input_error(dir.write(std::string("empty") + (name + 6), ""), ": is empty");
    }
    expect_input_error(dir.write("cube.xyz", cube_off()), "unknown mesh format '.xyz'");
    const std::string cube = dir.write("cube.off", cube_off());
    for (double bad : {0.0, -1.0, std::numeric_limits<double>::quiet_NaN(), std::numeric_limits<double>::infinity()})
        expect_input_error(cube, "mm_per_unit", bad);
}

TEST(MeshRead, ReadersPrintNothing)
{
    // The caller prints the one-line error; the readers themselves write nothing to the console
    // (OpenMesh, which read OBJ and PLY before, printed its own diagnostics).
    ::testing::internal::CaptureStderr();
    ::testing::internal::CaptureStdout();
    EXPECT_THROW((void)read_mesh(k_bad + "obj_bad_index.obj"), InputError);
    EXPECT_THROW((void)read_mesh(k_bad + "ply_bad_index.ply"), InputError);
    const test::ScratchDir dir;
    EXPECT_NO_THROW((void)read_mesh(dir.write("flipped.obj", cube_obj(true))));
    EXPECT_EQ(::testing::internal::GetCapturedStdout(), "");
    EXPECT_EQ(::testing::internal::GetCapturedStderr(), "");
}

TEST(MeshCheck, RejectsBadProgrammaticMeshes)
{
    TriangleMesh mesh;
    mesh.vertices = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}};
    EXPECT_THROW(check_mesh(mesh, "m"), InputError);
    mesh.triangles = {{0, 1, 3}};
    EXPECT_THROW(check_mesh(mesh, "m"), InputError);
    mesh.triangles = {{0, 1, 2}};
    EXPECT_NO_THROW(check_mesh(mesh, "m"));
    mesh.vertices[1].y() = std::numeric_limits<double>::infinity();
    EXPECT_THROW(check_mesh(mesh, "m"), InputError);
}

} // namespace
} // namespace vox::io
