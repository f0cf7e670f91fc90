// OBJ through read_mesh (src/io/obj_reader.cpp): the record forms it reads and ignores, and the
// damaged files it refuses naming the line.

#include "io/mesh.hpp"

#include "core/error.hpp"
#include "io/mesh_info.hpp"
#include "io/tetrahedron.hpp"
#include "test_support.hpp"

#include <gtest/gtest.h>

#include <string>

namespace vox::io {
namespace {

using test::error_of;
using test::expect_refused;

/// A tetrahedron (0,0,0) (10,0,0) (0,10,0) (0,0,10) with outward faces, volume 1000/6.
const char* const k_tetra_vertices = "v 0 0 0\nv 10 0 0\nv 0 10 0\nv 0 0 10\n";

TEST(ObjReader, EveryCornerFormAndIgnoredRecords)
{
    const test::ScratchDir dir;
    const std::string obj = "# exported by hand\nmtllib tetra.mtl\no tetra\ng body\ns 1\nusemtl red\n" +
                            std::string(k_tetra_vertices) +
                            "vt 0 0\nvt 1 0\nvt 0 1\nvn 0 0 -1\nvn 1 1 1\n"
                            "f 1 3 2\n"             // i
                            "f 1/1 2/2 4/3\n"       // i/j
                            "f 2//2 3//2 4//2\n"    // i//k
                            "f 1/1/1 4/2/1 3/3/1\n" // i/j/k
                            "l 1 2\n";
    test::expect_tetrahedron(read_mesh(dir.write("tetra.obj", obj)));
}

TEST(ObjReader, NegativeIndicesCountBackFromTheLatestVertex)
{
    const test::ScratchDir dir;
    // After 4 vertices, -4 is vertex 1 and -1 is vertex 4.
    const std::string obj = std::string(k_tetra_vertices) + "f -4 -2 -3\nf -4 -3 -1\nf -3 -2 -1\nf -4 -1 -2\n";
    test::expect_tetrahedron(read_mesh(dir.write("relative.obj", obj)));
}

TEST(ObjReader, PolygonsAreFanTriangulatedAndWIsIgnored)
{
    const test::ScratchDir dir;
    // A unit square as one quad, vertices with a weight w, a comment after a record, CRLF lines
    // and a record continued on the next line.
    const std::string obj = "v 0 0 0 1\r\nv 1 0 0 1\r\nv 1 1 0 1 # corner\r\nv 0 1 0\r\nf 1 2 \\\r\n 3 4\r\n";
    const TriangleMesh mesh = read_mesh(dir.write("quad.obj", obj));
    ASSERT_EQ(mesh.vertices.size(), 4u);
    ASSERT_EQ(mesh.triangles.size(), 2u);
    EXPECT_EQ(mesh.triangles[0], Eigen::Vector3i(0, 1, 2));
    EXPECT_EQ(mesh.triangles[1], Eigen::Vector3i(0, 2, 3));
    EXPECT_NEAR(mesh_info(mesh).area_mm2, 1.0, 1e-12);
}

TEST(ObjReader, ByteOrderMarkIsSkipped)
{
    const test::ScratchDir dir;
    const std::string obj = "\xEF\xBB\xBF" + std::string(k_tetra_vertices) + "f 1 3 2\nf 1 2 4\nf 2 3 4\nf 1 4 3\n";
    test::expect_tetrahedron(read_mesh(dir.write("bom.obj", obj)));
}

TEST(ObjReader, FacesMayComeBeforeTheirVertices)
{
    const test::ScratchDir dir;
    const std::string obj = "f 1 3 2\nf 1 2 4\nf 2 3 4\nf 1 4 3\n" + std::string(k_tetra_vertices);
    test::expect_tetrahedron(read_mesh(dir.write("faces_first.obj", obj)));
}

TEST(ObjReader, NonFiniteVertexIsRefusedNotDropped)
{
    // OpenMesh dropped "v nan 10 0" and shifted every later index: this tetrahedron imported as
    // another shape. It must be refused, naming the vertex and its line.
    const test::ScratchDir dir;
    for (const char* bad : {"nan", "inf", "-inf", "NaN"}) {
        SCOPED_TRACE(bad);
        const std::string obj = "v 0 0 0\nv " + std::string(bad) +
                                " 10 0\nv 0 10 0\nv 0 0 10\nf 1 3 2\nf 1 2 4\nf 2 3 4\nf 1 4 3\n";
        const std::string path = dir.write("nan.obj", obj);
        expect_refused([&] { (void)read_mesh(path); }, path + ": line 2: vertex 2 has a non-finite coordinate",
                       "non-finite");
    }
}

TEST(ObjReader, MalformedRecordsNameTheLine)
{
    const test::ScratchDir dir;
    const std::string v3 = "v 0 0 0\nv 1 0 0\nv 0 1 0\n";
    const auto refused = [&](const std::string& name, const std::string& text, const std::string& problem) {
        SCOPED_TRACE(name);
        const std::string path = dir.write(name, text);
        const std::string message = error_of([&] { (void)read_mesh(path); });
        EXPECT_EQ(message.rfind(path + ": " + problem, 0), 0u) << message;
        EXPECT_EQ(message.find('\n'), std::string::npos) << message;
    };
    refused("index_beyond.obj", v3 + "f 1 2 4\n", "line 4: face references vertex 4, but the file has only 3 vertices");
    refused("index_zero.obj", v3 + "f 0 1 2\n", "line 4: face references vertex 0");
    refused("relative_before_first.obj", v3 + "f -1 -2 -4\n",
            "line 4: face references vertex -4 (counting back), but only 3 vertices are defined before it");
    refused("two_corners.obj", v3 + "f 1 2\n", "line 4: a face needs at least 3 vertices, this one has 2");
    refused("bad_corner.obj", v3 + "f 1 2 x\n", "line 4: face corner 'x' is not a vertex index");
    refused("bad_corner_slashes.obj", v3 + "f 1 2 3/1/1/1\n", "line 4: face corner '3/1/1/1' is not a vertex index");
    refused("bad_texture_index.obj", v3 + "f 1 2 3/a\n", "line 4: face corner '3/a' is not a vertex index");
    refused("short_vertex.obj", "v 0 0\n", "line 1: vertex 1 has fewer than 3 coordinates");
    refused("not_a_number.obj", "v 0 zero 0\n", "line 1: vertex 1: 'zero' is not a number");
    refused("no_faces.obj", v3 + "vn 0 0 1\n", "has no faces (no 'f' record; 3 vertices)");
    refused("comments_only.obj", "# nothing\n\n", "has no faces");
    refused("misspelt.obj", v3 + "vv 0 0 1\nf 1 2 3\n", "line 4: unknown record 'vv' (not an OBJ keyword)");
    refused("binary.obj", std::string("v 0 0 0\n\0\1\2\3", 12), "not an OBJ file: it holds binary data");
}

} // namespace
} // namespace vox::io
