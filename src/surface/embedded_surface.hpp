#pragma once
// The object's surface: marching cubes over the fine voxels with voxel centres as cube corners
// (cube_polygons.hpp), every vertex embedded by trilinear coordinates in the element of the
// simulated level that holds the voxel it belongs to, so the deformed surface follows the element
// nodes. One surface serves pictures, contact and export. Removing voxels or disconnecting faces
// recomputes only the cubes that touch them; the result equals a fresh extraction.

#include "grid/branched_grid.hpp"
#include "surface/cube_polygons.hpp"

#include <Eigen/Core>

#include <array>
#include <cstdint>
#include <span>
#include <unordered_map>
#include <vector>

namespace vox::surface {

struct SurfaceVertex {
    std::uint64_t key = 0;            ///< identity: voxel face, face centre or cube centre (see .cpp)
    std::uint32_t voxel = 0;          ///< the fine voxel (slot) it belongs to
    Eigen::Vector3d rest{0, 0, 0};    ///< rest position in the grid's index space (voxel units)
    std::uint32_t element = 0;        ///< element of the simulated level holding `voxel`
    Eigen::Vector3d local{0, 0, 0};   ///< trilinear coordinates in that element's cell
    std::int32_t label = 0;           ///< material label of `voxel`
    std::uint32_t users = 0;          ///< triangles using it; 0 marks a free slot
};

/// A compact copy of the surface: positions in world millimetres, triangles with outward normals
/// in world space, one label per vertex.
struct SurfaceMesh {
    std::vector<Eigen::Vector3d> positions;
    std::vector<Eigen::Vector3i> triangles;
    std::vector<std::int32_t> labels;
};

class EmbeddedSurface {
public:
    /// Extracts the whole surface of `grid`'s voxels, embedded at `level` (1 .. grid.max_level()).
    EmbeddedSurface(const grid::BranchedGrid& grid, int level);

    /// Brings the surface up to date after `grid.update(removed, faces)` returned `report`.
    void update(const grid::BranchedGrid& grid, std::span<const grid::Coord> removed,
                std::span<const std::pair<grid::Coord, int>> faces, const grid::UpdateReport& report);

    [[nodiscard]] int level() const { return m_level; }
    /// The same surface embedded at another level (1 .. grid.max_level()) of the same grid: a
    /// simulation moving to another level keeps its surface, cuts and smoothing included.
    void reembed(const grid::BranchedGrid& grid, int level);
    [[nodiscard]] std::size_t vertex_count() const { return m_vertex_count; }
    [[nodiscard]] std::size_t triangle_count() const { return m_triangle_count; }
    /// True when the index-to-world map mirrors: the triangle slots' corner order then gives
    /// inward normals in world space (mesh() flips them).
    [[nodiscard]] bool mirrored() const { return m_flip; }
    /// Vertex slots (users == 0: free) and triangle slots (a free one has vertex no_index).
    [[nodiscard]] const std::vector<SurfaceVertex>& vertices() const { return m_vertices; }
    [[nodiscard]] const std::vector<std::array<std::uint32_t, 3>>& triangles() const { return m_triangles; }
    /// Triangle slots using vertex slot `v`, in increasing order (kept up to date as cuts change
    /// the surface, so that a model rebuilt after a cut does not group them again).
    [[nodiscard]] std::span<const std::uint32_t> vertex_triangles(std::uint32_t v) const { return m_vertex_triangles[v]; }
    /// Vertex slots embedded in element `element` of the level (kept up to date likewise).
    [[nodiscard]] std::span<const std::uint32_t> element_vertices(std::uint32_t element) const
    {
        return element < m_element_vertices.size() ? std::span<const std::uint32_t>(m_element_vertices[element])
                                                    : std::span<const std::uint32_t>();
    }
    /// Calls f(slot) for each vertex slot belonging to fine voxel `voxel`.
    template <class F> void for_each_voxel_vertex(std::uint32_t voxel, F&& f) const
    {
        if (voxel >= m_owned.size() || m_owned[voxel] == 0) return;
        for (std::uint64_t dir = 0; dir < 6; ++dir) // crossings on the voxel's six edges' directions
            if (const std::uint32_t id = m_vertex_index.find((std::uint64_t{voxel} * 6 + dir) << 2); id != grid::CoordMap::missing) f(id);
        auto [first, last] = m_centre_vertices.equal_range(voxel);
        for (auto it = first; it != last; ++it) f(it->second);
    }

    /// Deformed vertex positions (per vertex slot, world mm) from the level's node positions
    /// (per node id, world mm): x = sum over corners of N_c(local) * node position.
    void deform(const grid::BranchedGrid& grid, std::span<const Eigen::Vector3d> node_positions,
                std::vector<Eigen::Vector3d>& out) const;
    /// The surface at rest, or deformed by `node_positions`, as a compact mesh.
    [[nodiscard]] SurfaceMesh mesh(const grid::BranchedGrid& grid) const;
    [[nodiscard]] SurfaceMesh mesh(const grid::BranchedGrid& grid, std::span<const Eigen::Vector3d> node_positions) const;

    /// Taubin smoothing of the rest positions (lambda 0.5, mu -0.53 per iteration pair), each
    /// vertex staying embedded in its element: its trilinear coordinates are recomputed there.
    void smooth(const grid::BranchedGrid& grid, int iterations);

    /// Windowed-sinc low-pass smoothing of the rest positions (Taubin, Zhang and Golub 1996, the
    /// filter behind 3D Slicer's surface smoothing): a Chebyshev polynomial of the neighbour
    /// average, of degree `iterations`, that passes the shape's low frequencies unchanged and
    /// removes those above `passband` (slice terraces, voxel steps). A uniform move along the
    /// vertex normals then restores the volume the surface enclosed before. Each vertex stays
    /// embedded in its element. Returns the relative volume change before that restoration.
    double smooth_windowed_sinc(const grid::BranchedGrid& grid, int iterations, double passband);

    /// The volume the surface encloses at rest, mm^3 (divergence theorem over its triangles).
    [[nodiscard]] double rest_volume_mm3(const grid::BranchedGrid& grid) const;

private:
    void extract_cube(const grid::BranchedGrid& grid, const grid::Coord& cube);
    void clear_cube(std::uint64_t cube_key);
    std::uint32_t vertex_for(const grid::BranchedGrid& grid, const grid::Coord& cube, const CubeVertex& v,
                             const std::array<std::uint32_t, 8>& corners);
    void embed(const grid::BranchedGrid& grid, SurfaceVertex& v) const;
    /// embed(), and the vertex moved to its element's list.
    void place(const grid::BranchedGrid& grid, std::uint32_t v);
    void unlist(std::uint32_t v);
    void release_vertex(std::uint32_t v);
    /// Each used vertex slot's neighbours along triangle edges (sorted, unique).
    [[nodiscard]] std::vector<std::vector<std::uint32_t>> vertex_neighbours() const;
    /// Sets the rest positions from world-space points (per vertex slot) and re-embeds them.
    void set_rest_world(const grid::BranchedGrid& grid, const std::vector<Eigen::Vector3d>& x);
    [[nodiscard]] std::uint64_t cube_key(const grid::Coord& cube) const;

    int m_level = 1;
    grid::Coord m_origin{0, 0, 0};
    std::vector<SurfaceVertex> m_vertices;
    std::vector<std::uint32_t> m_free_vertices;
    grid::CoordMap m_vertex_index; ///< key -> vertex slot (missing when freed)
    std::vector<std::array<std::uint32_t, 3>> m_triangles;
    std::vector<std::uint32_t> m_free_triangles;
    std::unordered_map<std::uint64_t, std::vector<std::uint32_t>> m_cube_triangles;
    /// Face- and cube-centre vertices by the voxel they belong to (crossings are found by key).
    std::unordered_multimap<std::uint32_t, std::uint32_t> m_centre_vertices;
    /// Per voxel slot: how many vertices belong to it, so that re-embedding after a cut visits
    /// only the few voxels of an element that carry surface.
    std::vector<std::uint16_t> m_owned;
    /// Per vertex slot: its triangle slots (sorted); per element of the level: its vertex slots,
    /// and per vertex slot its place in that list (no_index: listed nowhere).
    std::vector<std::vector<std::uint32_t>> m_vertex_triangles;
    std::vector<std::vector<std::uint32_t>> m_element_vertices;
    std::vector<std::uint32_t> m_list_place;
    std::size_t m_vertex_count = 0;
    std::size_t m_triangle_count = 0;
    bool m_flip = false; ///< the index-to-world transform mirrors: flip windings in world space
    /// Triangulations by cube configuration (8 presence bits, 12 connection bits), filled on demand.
    std::unordered_map<std::uint32_t, CubeCase> m_cases;
};

} // namespace vox::surface
