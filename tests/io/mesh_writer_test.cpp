#include "io/mesh_writer.hpp"

#include "io/mesh.hpp"
#include "io/mesh_info.hpp"
#include "test_support.hpp"

#include <gtest/gtest.h>

#include <filesystem>

using namespace vox;

namespace {
/// A closed, outward cube of edge 2 mm with corner (1, -3, 0.5).
io::TriangleMesh cube()
{
    io::TriangleMesh m;
    for (int c = 0; c < 8; ++c) m.vertices.emplace_back(1 + 2 * (c & 1), -3 + 2 * ((c >> 1) & 1), 0.5 + 2 * ((c >> 2) & 1));
    const int quads[6][4] = {{0, 2, 3, 1}, {4, 5, 7, 6}, {0, 1, 5, 4}, {2, 6, 7, 3}, {0, 4, 6, 2}, {1, 3, 7, 5}};
    for (const auto& q : quads) {
        m.triangles.emplace_back(q[0], q[1], q[2]);
        m.triangles.emplace_back(q[0], q[2], q[3]);
    }
    return m;
}
} // namespace

TEST(MeshWriter, EveryFormatReadsBackTheSameClosedSolid)
{
    const test::ScratchDir dir;
    const io::TriangleMesh m = cube();
    ASSERT_NEAR(io::mesh_info(m).enclosed_volume_mm3, 8.0, 1e-12);
    const std::vector<std::int32_t> labels(8, 255);
    for (const char* ext : {".obj", ".ply", ".stl", ".off"}) {
        SCOPED_TRACE(ext);
        const std::string path = dir.path(std::string("cube") + ext);
        io::write_mesh(path, m.vertices, m.triangles, labels);
        const io::TriangleMesh r = io::read_mesh(path);
        EXPECT_EQ(r.triangles.size(), 12u);
        EXPECT_EQ(r.vertices.size(), 8u);
        const io::MeshInfo info = io::mesh_info(r);
        EXPECT_TRUE(info.closed);
        EXPECT_TRUE(info.consistently_oriented);
        EXPECT_NEAR(info.enclosed_volume_mm3, 8.0, 1e-5);
    }
    EXPECT_EQ(std::distance(std::filesystem::directory_iterator(dir.root()), {}), 4); // no temporaries left
}

TEST(MeshWriter, RefusesUnknownFormatsWithoutWriting)
{
    const test::ScratchDir dir;
    const io::TriangleMesh m = cube();
    test::expect_refused([&] { io::write_mesh(dir.path("cube.xyz"), m.vertices, m.triangles); }, dir.path("cube.xyz"),
                         "unknown mesh format");
    EXPECT_TRUE(std::filesystem::is_empty(dir.root()));
}
