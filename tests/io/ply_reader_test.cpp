// PLY through read_mesh (src/io/ply_reader.cpp): ascii and binary of both byte orders, properties
// and elements it reads past, and the damaged files it refuses.

#include "io/mesh.hpp"

#include "core/error.hpp"
#include "io/mesh_info.hpp"
#include "io/tetrahedron.hpp"
#include "test_support.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <bit>
#include <cstdint>
#include <cstring>
#include <limits>
#include <string>
#include <vector>

namespace vox::io {
namespace {

using test::error_of;

/// The tetrahedron (0,0,0) (10,0,0) (0,10,0) (0,0,10), faces outward.
const double k_points[4][3] = {{0, 0, 0}, {10, 0, 0}, {0, 10, 0}, {0, 0, 10}};
const int k_faces[4][3] = {{0, 2, 1}, {0, 1, 3}, {1, 2, 3}, {0, 3, 2}};

/// Appends the bytes of `value` in the given byte order.
template <class T> void put(std::string& out, T value, bool big_endian)
{
    char bytes[sizeof(T)];
    std::memcpy(bytes, &value, sizeof(T));
    if (big_endian != (std::endian::native == std::endian::big)) std::reverse(bytes, bytes + sizeof(T));
    out.append(bytes, sizeof(T));
}

/// A binary tetrahedron with what real files carry besides: an element before the vertices (with
/// a list), double coordinates between a normal and a colour, a face property after the index
/// list (uint indices, ushort counts), and an edge element after the faces.
std::string binary_tetrahedron(bool big_endian)
{
    std::string s = std::string("ply\nformat ") + (big_endian ? "binary_big_endian" : "binary_little_endian") +
                    " 1.0\ncomment made by hand\nobj_info nothing\n"
                    "element material 1\nproperty uchar red\nproperty list uchar float shininess\n"
                    "element vertex 4\nproperty float nx\nproperty double x\nproperty double y\nproperty double z\n"
                    "property uchar red\nproperty uchar green\nproperty uchar blue\n"
                    "element face 4\nproperty list ushort uint vertex_indices\nproperty int flags\n"
                    "element edge 2\nproperty int vertex1\nproperty int vertex2\nproperty list uchar short extra\n"
                    "end_header\n";
    put<std::uint8_t>(s, 200, big_endian);
    put<std::uint8_t>(s, 2, big_endian);
    put<float>(s, 0.5f, big_endian);
    put<float>(s, 0.25f, big_endian);
    for (const auto& p : k_points) {
        put<float>(s, 1.0f, big_endian);
        for (const double c : p) put<double>(s, c, big_endian);
        for (int rgb = 0; rgb < 3; ++rgb) put<std::uint8_t>(s, 255, big_endian);
    }
    for (const auto& f : k_faces) {
        put<std::uint16_t>(s, 3, big_endian);
        for (const int i : f) put<std::uint32_t>(s, static_cast<std::uint32_t>(i), big_endian);
        put<std::int32_t>(s, -1, big_endian);
    }
    for (int e = 0; e < 2; ++e) {
        put<std::int32_t>(s, e, big_endian);
        put<std::int32_t>(s, e + 1, big_endian);
        put<std::uint8_t>(s, 1, big_endian);
        put<std::int16_t>(s, 7, big_endian);
    }
    return s;
}

std::string ascii_header(int vertices, int faces)
{
    return "ply\nformat ascii 1.0\nelement vertex " + std::to_string(vertices) +
           "\nproperty float x\nproperty float y\nproperty float z\nelement face " + std::to_string(faces) +
           "\nproperty list uchar int vertex_indices\nend_header\n";
}

const std::string k_ascii_vertices = "0 0 0\n10 0 0\n0 10 0\n0 0 10\n";
const std::string k_ascii_faces = "3 0 2 1\n3 0 1 3\n3 1 2 3\n3 0 3 2\n";

TEST(PlyReader, BinaryBothByteOrdersWithSkippedPropertiesAndElements)
{
    const test::ScratchDir dir;
    test::expect_tetrahedron(read_mesh(dir.write("le.ply", binary_tetrahedron(false))));
    test::expect_tetrahedron(read_mesh(dir.write("be.ply", binary_tetrahedron(true))));
}

TEST(PlyReader, AsciiWithSkippedPropertiesAndElements)
{
    const test::ScratchDir dir;
    const std::string ply = "ply\r\nformat ascii 1.0\r\ncomment CRLF lines\r\n"
                            "element vertex 4\r\nproperty double x\r\nproperty double y\r\nproperty double z\r\n"
                            "property float quality\r\n"
                            "element face 4\r\nproperty uchar flags\r\nproperty list uint8 int32 vertex_index\r\n"
                            "element edge 1\r\nproperty list uchar int corners\r\nend_header\r\n"
                            "0 0 0 0.5\r\n10 0 0 0.5\r\n0 10 0 0.5\r\n0 0 10 0.5\r\n\r\n"
                            "1 3 0 2 1\r\n1 3 0 1 3\r\n1 3 1 2 3\r\n1 3 0 3 2\r\n2 0 1\r\n";
    test::expect_tetrahedron(read_mesh(dir.write("crlf.ply", ply)));
}

TEST(PlyReader, PolygonsAreFanTriangulated)
{
    const test::ScratchDir dir;
    const std::string ply = ascii_header(4, 1) + "0 0 0\n1 0 0\n1 1 0\n0 1 0\n4 0 1 2 3\n";
    const TriangleMesh mesh = read_mesh(dir.write("quad.ply", ply));
    ASSERT_EQ(mesh.triangles.size(), 2u);
    EXPECT_EQ(mesh.triangles[1], Eigen::Vector3i(0, 2, 3));
}

TEST(PlyReader, OutOfRangeFaceIsRefusedNotDropped)
{
    // OpenMesh dropped the face using vertex 9 and loaded 3 faces without error.
    const test::ScratchDir dir;
    const std::string ascii = ascii_header(4, 4) + k_ascii_vertices + "3 0 2 1\n3 0 1 3\n3 1 2 9\n3 0 3 2\n";
    const std::string path = dir.write("bad_index.ply", ascii);
    EXPECT_EQ(error_of([&] { (void)read_mesh(path); }),
              path + ": line 16: face 2 references vertex 9, but there are only 4 vertices");

    std::string binary = binary_tetrahedron(false);
    // The last index of the last face, followed by its int flags and the two 11-byte edges.
    const std::size_t index_at = binary.size() - 2 * 11 - 4 - 4;
    const std::uint32_t nine = 9;
    std::memcpy(binary.data() + index_at, &nine, 4);
    const std::string binary_path = dir.write("bad_index_binary.ply", binary);
    EXPECT_EQ(error_of([&] { (void)read_mesh(binary_path); }),
              binary_path + ": face 3 references vertex 9, but there are only 4 vertices");
}

TEST(PlyReader, MalformedFilesNameTheProblem)
{
    const test::ScratchDir dir;
    const auto refused = [&](const std::string& name, const std::string& text, const std::string& problem) {
        SCOPED_TRACE(name);
        const std::string path = dir.write(name, text);
        const std::string message = error_of([&] { (void)read_mesh(path); });
        EXPECT_EQ(message.rfind(path + ": ", 0), 0u) << message;
        EXPECT_NE(message.find(problem), std::string::npos) << message;
        EXPECT_EQ(message.find('\n'), std::string::npos) << message;
    };
    const std::string tetra = ascii_header(4, 4) + k_ascii_vertices + k_ascii_faces;
    const std::string binary = binary_tetrahedron(false);

    // Header.
    refused("magic.ply", "PLY\n" + tetra.substr(4), "not a PLY file");
    refused("no_end_header.ply", "ply\nformat ascii 1.0\nelement vertex 0\n", "no 'end_header' line");
    refused("no_format.ply", "ply\nelement vertex 0\nend_header\n", "no 'format' line");
    refused("format.ply", "ply\nformat binary_middle_endian 1.0\nend_header\n",
            "header line 2: unsupported format 'binary_middle_endian'");
    refused("version.ply", "ply\nformat ascii 2.0\nend_header\n", "unsupported PLY version '2.0'");
    refused("type.ply", "ply\nformat ascii 1.0\nelement vertex 1\nproperty real x\nend_header\n",
            "header line 4: unknown property type 'real'");
    refused("count_type.ply",
            "ply\nformat ascii 1.0\nelement face 1\nproperty list float int vertex_indices\nend_header\n",
            "list count type 'float' is not an integer type");
    refused("keyword.ply", "ply\nformat ascii 1.0\nelemnt vertex 1\nend_header\n", "unknown header keyword 'elemnt'");
    refused("count.ply", "ply\nformat ascii 1.0\nelement vertex -1\nend_header\n", "non-negative count");
    refused("orphan_property.ply", "ply\nformat ascii 1.0\nproperty float x\nend_header\n",
            "a property before any 'element' line");
    refused("no_z.ply", "ply\nformat ascii 1.0\nelement vertex 0\nproperty float x\nproperty float y\nend_header\n",
            "element vertex has no property 'z'");
    refused("no_face_element.ply", "ply\nformat ascii 1.0\nelement vertex 0\nproperty float x\nproperty float y\n"
                                   "property float z\nend_header\n",
            "has no faces (no 'element face'");
    refused("no_index_list.ply", ascii_header(4, 4).replace(ascii_header(4, 4).find("vertex_indices"), 14, "corners"),
            "element face has no list property 'vertex_indices'");
    refused("float_indices.ply", ascii_header(4, 4).replace(ascii_header(4, 4).find("int vertex"), 3, "float"),
            "face property 'vertex_indices' must be a list of integers");

    // Ascii data.
    refused("nan.ply", ascii_header(4, 4) + "0 0 0\n10 nan 0\n0 10 0\n0 0 10\n" + k_ascii_faces,
            "line 11: vertex 1 has a non-finite coordinate (10, nan, 0)");
    refused("inf.ply", ascii_header(4, 4) + "0 0 0\n10 0 0\n0 10 0\n0 0 -inf\n" + k_ascii_faces,
            "line 13: vertex 3 has a non-finite coordinate (0, 0, -inf)");
    refused("word.ply", ascii_header(4, 4) + "0 0 0\n10 zero 0\n", "line 11: 'zero' is not a number");
    refused("few_values.ply", ascii_header(4, 4) + "0 0 0\n10 0\n",
            "line 11: vertex 1 has fewer values than its properties");
    refused("many_values.ply", ascii_header(4, 4) + "0 0 0 0\n", "line 10: more values than the element's properties");
    refused("short_list.ply", ascii_header(4, 4) + k_ascii_vertices + "3 0 2\n",
            "line 14: face 0 has fewer values than its properties");
    refused("two_corners.ply", ascii_header(4, 4) + k_ascii_vertices + "2 0 2\n",
            "line 14: face 0 has 2 vertices; a face needs at least 3");
    refused("negative_index.ply", ascii_header(4, 4) + k_ascii_vertices + "3 0 -1 2\n",
            "line 14: face 0 references vertex -1");
    refused("count_range.ply", ascii_header(4, 4) + k_ascii_vertices + "300 0 1 2\n",
            "line 14: '300' does not fit its property's type");
    refused("truncated_ascii.ply", ascii_header(4, 4) + k_ascii_vertices + "3 0 2 1\n",
            "truncated: the data ends in face 1 of the 4 the header declares");
    refused("extra_ascii.ply", tetra + "3 0 1 2\n", "line 18: data after the last element the header declares");
    refused("zero_faces.ply", ascii_header(4, 0) + k_ascii_vertices, "has no faces ('element face 0'");

    // Binary data.
    refused("truncated_binary.ply", binary.substr(0, binary.size() - 30),
            "truncated: the data ends in face 3 of the 4 the header declares");
    refused("truncated_skipped.ply", binary.substr(0, binary.size() - 5),
            "truncated: the data ends in edge 1 of the 2 the header declares");
    refused("extra_binary.ply", binary + "abc", "holds 3 bytes after the last element the header declares");
    std::string nan_binary = binary;
    const double nan = std::numeric_limits<double>::quiet_NaN();
    // Vertex 2's y: after the material (1 + 1 + 8 bytes), two 31-byte vertices, a float and x.
    std::memcpy(nan_binary.data() + nan_binary.find("end_header\n") + 11 + 10 + 2 * 31 + 4 + 8, &nan, 8);
    refused("nan_binary.ply", nan_binary, "vertex 2 has a non-finite coordinate (0, nan, 0)");
}

TEST(PlyReader, TrailingLineBreakAfterBinaryDataIsAccepted)
{
    const test::ScratchDir dir;
    test::expect_tetrahedron(read_mesh(dir.write("newline.ply", binary_tetrahedron(false) + "\n")));
}

} // namespace
} // namespace vox::io
