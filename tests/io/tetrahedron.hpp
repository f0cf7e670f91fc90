#pragma once
// The closed tetrahedron the mesh-reader tests write in every format.

#include "io/mesh.hpp"
#include "io/mesh_info.hpp"

#include <gtest/gtest.h>

namespace vox::test {

/// Checks a mesh read back as the tetrahedron (0,0,0) (10,0,0) (0,10,0) (0,0,10) with outward
/// faces: 4 vertices, 4 triangles, closed, volume 1000 / 6.
inline void expect_tetrahedron(const io::TriangleMesh& mesh)
{
    const io::MeshInfo info = io::mesh_info(mesh);
    EXPECT_EQ(info.vertices, 4u);
    EXPECT_EQ(info.triangles, 4u);
    EXPECT_TRUE(info.closed);
    EXPECT_TRUE(info.consistently_oriented);
    EXPECT_NEAR(info.enclosed_volume_mm3, 1000.0 / 6.0, 1e-9);
}

} // namespace vox::test
