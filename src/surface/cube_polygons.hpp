#pragma once
// Marching cubes on voxel centres (Jerabkova et al. 2010, Figure 8): a cube's 8 corners are the
// centres of a 2 x 2 x 2 block of voxels, corner c having bits (+x, +y, +z); its 12 edges join
// face-adjacent voxels. Each connected component of the cube's present corners (6-connectivity
// through connected faces) is polygonised on its own, so voxels that are not connected never
// share a sheet. On every cube face the decision is taken from that face alone (present corners
// that are not joined through a connected face edge are always separated), so the two cubes
// sharing a face agree and the surface is closed. A face whose four corners are one component
// with a single disconnected edge (the end of a cut that does not go through) gets a vertex at the
// face centre. Loops through such vertices, and loops that cross one face twice (two diagonal
// corners of a face joined through the rest of the cube), are closed with a vertex at the cube
// centre: a fan there could put a chord in the face that the neighbouring cube also uses.

#include <array>
#include <cstdint>
#include <vector>

namespace vox::surface {

/// Corner pairs of the 12 cube edges; edge e joins corners edge_corners[e][0] (the lower) and
/// [1] along axis edge_axis[e].
inline constexpr std::array<std::array<int, 2>, 12> edge_corners{{{0, 1}, {2, 3}, {4, 5}, {6, 7}, {0, 2}, {1, 3},
                                                                  {4, 6}, {5, 7}, {0, 4}, {1, 5}, {2, 6}, {3, 7}}};
inline constexpr std::array<int, 12> edge_axis{0, 0, 0, 0, 1, 1, 1, 1, 2, 2, 2, 2};

/// A vertex of a cube's polygons.
struct CubeVertex {
    enum class Kind : std::uint8_t {
        crossing,    ///< on edge `index`, belonging to the present corner `corner` (at the edge's midpoint)
        face_centre, ///< at the centre of face `index` (2 axis + side), belonging to corner `corner`'s component
        cube_centre, ///< at the cube centre, closing one loop: `corner` and `index` are those of the
                     ///< loop's first (crossing) vertex, which names the loop
    };
    Kind kind = Kind::crossing;
    std::uint8_t corner = 0;
    std::uint8_t index = 0;
    friend bool operator==(const CubeVertex&, const CubeVertex&) = default;
};

/// One closed loop of a component's surface inside the cube, oriented so that its normal (right
/// hand) points out of the material. Loops are fanned from their first vertex unless they need a
/// cube-centre vertex (see above): then one triangle joins it to each loop edge.
struct CubeLoop {
    std::vector<CubeVertex> vertices;
    bool needs_centre = false;
    bool closed = true; ///< the chain of face segments came back to its start (always, for valid input)
};

/// The triangles of one cube configuration, as corner/edge/face references.
struct CubeCase {
    std::vector<std::array<CubeVertex, 3>> triangles;
};

/// Polygonises the cube whose present corners are the bits of `present` (8 bits) and whose edges
/// joining two present corners through a connected face are the bits of `connected` (12 bits;
/// bits of edges with an absent corner are ignored).
[[nodiscard]] std::vector<CubeLoop> polygonise_cube(std::uint8_t present, std::uint16_t connected);

/// The triangles of polygonise_cube, triangulated as described above; deterministic.
[[nodiscard]] CubeCase triangulate_cube(std::uint8_t present, std::uint16_t connected);

/// Cube-local position (each coordinate 0, 0.5 or 1) of a cube vertex.
[[nodiscard]] std::array<double, 3> cube_vertex_position(const CubeVertex& v);

} // namespace vox::surface
