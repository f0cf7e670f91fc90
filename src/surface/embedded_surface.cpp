#include "surface/embedded_surface.hpp"

#include "core/error.hpp"
#include "core/morton.hpp"
#include "core/progress.hpp"

#include <Eigen/Geometry>
#include <Eigen/LU>

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace vox::surface {
namespace {

// Vertex keys: the low 2 bits say what the vertex is.
//  - crossing: the face of voxel `slot` in direction `dir` (2 axis + (1 if +)): (6 slot + dir) << 2;
//  - face centre: the marching-cubes face whose lowest corner is voxel index p, normal `axis`:
//    (3 morton(p - origin) + axis) << 2 | 1;
//  - cube centre: the cube with lowest corner p, for the loop whose first vertex is the crossing
//    (corner, edge): (128 morton(p - origin) + 8 edge + corner) << 2 | 2.
// Coordinates relative to the origin stay below 2^18 so the keys fit 64 bits.
constexpr int k_max_extent = (1 << 18) - 4;

std::uint64_t morton(const grid::Coord& local)
{
    return morton_encode(static_cast<std::uint32_t>(local.x()), static_cast<std::uint32_t>(local.y()),
                         static_cast<std::uint32_t>(local.z()));
}

grid::Coord corner_offset(int c) { return {c & 1, (c >> 1) & 1, (c >> 2) & 1}; }

} // namespace

EmbeddedSurface::EmbeddedSurface(const grid::BranchedGrid& grid, int level) : m_level(level)
{
    if (level < 1 || level > grid.max_level())
        throw InputError("the surface is embedded at a level from 1 to " + std::to_string(grid.max_level()) +
                         ", got " + std::to_string(level));
    const grid::FineVoxels& voxels = grid.voxels();
    m_origin = voxels.origin() - grid::Coord::Ones();
    m_flip = voxels.index_to_world().topLeftCorner<3, 3>().determinant() < 0.0;
    m_owned.assign(voxels.slots(), 0);

    // Surface cubes: the four cubes around every voxel face that is exposed (no neighbour, or a
    // disconnected one). All other cubes are entirely inside or outside.
    std::vector<std::uint64_t> cubes;
    for (std::uint32_t v = 0; v < voxels.slots(); ++v) {
        if (!voxels.alive(v)) continue;
        int linked = 0;
        voxels.for_each_link(v, [&](std::uint32_t, int dir) { linked |= 1 << dir; });
        if (linked == 0x3f) continue;
        const grid::Coord p = voxels.coord(v);
        if (((p - m_origin).array() >= k_max_extent).any())
            throw InputError("the object is too large for the surface (more than 2^18 voxels along an axis)");
        for (int dir = 0; dir < 6; ++dir) {
            if (linked & (1 << dir)) continue;
            const int axis = dir / 2, u = (axis + 1) % 3, w = (axis + 2) % 3;
            grid::Coord m = p;
            if (!(dir & 1)) --m[axis];
            for (int k = 0; k < 4; ++k) {
                grid::Coord c = m;
                c[u] -= k & 1;
                c[w] -= (k >> 1) & 1;
                cubes.push_back(morton(c - m_origin));
            }
        }
    }
    std::sort(cubes.begin(), cubes.end());
    cubes.erase(std::unique(cubes.begin(), cubes.end()), cubes.end());
    m_vertex_index = grid::CoordMap(cubes.size());
    m_cube_triangles.reserve(cubes.size());
    for (std::uint64_t key : cubes) {
        const grid::Coord local(static_cast<int>(morton_decode_axis(key, 0)), static_cast<int>(morton_decode_axis(key, 1)),
                                static_cast<int>(morton_decode_axis(key, 2)));
        extract_cube(grid, local + m_origin);
    }
}

std::uint64_t EmbeddedSurface::cube_key(const grid::Coord& cube) const { return morton(cube - m_origin); }

void EmbeddedSurface::extract_cube(const grid::BranchedGrid& grid, const grid::Coord& cube)
{
    const grid::FineVoxels& voxels = grid.voxels();
    const std::uint64_t key = cube_key(cube);
    clear_cube(key);

    std::array<std::uint32_t, 8> corners{};
    std::uint32_t present = 0, connected = 0;
    for (int c = 0; c < 8; ++c) {
        corners[c] = voxels.find(cube + corner_offset(c));
        if (corners[c] != grid::FineVoxels::missing) present |= 1u << c;
    }
    for (int e = 0; e < 12; ++e) {
        const std::uint32_t a = corners[edge_corners[e][0]], b = corners[edge_corners[e][1]];
        if (a != grid::FineVoxels::missing && b != grid::FineVoxels::missing && !voxels.face_disconnected(a, edge_axis[e]))
            connected |= 1u << e;
    }
    if (present == 0 || (present == 0xff && connected == 0xfff)) return;

    const std::uint32_t state = present | connected << 8;
    auto it = m_cases.find(state);
    if (it == m_cases.end())
        it = m_cases.emplace(state, triangulate_cube(static_cast<std::uint8_t>(present), static_cast<std::uint16_t>(connected)))
                 .first;
    if (it->second.triangles.empty()) return;

    std::vector<std::uint32_t>& ids = m_cube_triangles[key];
    for (const auto& tri : it->second.triangles) {
        std::array<std::uint32_t, 3> t{};
        for (int k = 0; k < 3; ++k) t[k] = vertex_for(grid, cube, tri[k], corners);
        std::uint32_t id;
        if (!m_free_triangles.empty()) {
            id = m_free_triangles.back();
            m_free_triangles.pop_back();
            m_triangles[id] = t;
        } else {
            id = static_cast<std::uint32_t>(m_triangles.size());
            m_triangles.push_back(t);
        }
        for (std::uint32_t v : t) {
            std::vector<std::uint32_t>& list = m_vertex_triangles[v];
            list.insert(std::upper_bound(list.begin(), list.end(), id), id);
        }
        ids.push_back(id);
        ++m_triangle_count;
    }
}

void EmbeddedSurface::clear_cube(std::uint64_t key)
{
    const auto it = m_cube_triangles.find(key);
    if (it == m_cube_triangles.end()) return;
    for (std::uint32_t id : it->second) {
        for (std::uint32_t v : m_triangles[id]) {
            std::vector<std::uint32_t>& list = m_vertex_triangles[v];
            list.erase(std::lower_bound(list.begin(), list.end(), id));
            release_vertex(v);
        }
        m_triangles[id] = {grid::no_index, grid::no_index, grid::no_index};
        m_free_triangles.push_back(id);
        --m_triangle_count;
    }
    m_cube_triangles.erase(it);
}

std::uint32_t EmbeddedSurface::vertex_for(const grid::BranchedGrid& grid, const grid::Coord& cube, const CubeVertex& cv,
                                          const std::array<std::uint32_t, 8>& corners)
{
    std::uint64_t key = 0;
    std::uint32_t voxel = 0;
    switch (cv.kind) {
    case CubeVertex::Kind::crossing: {
        const int axis = edge_axis[cv.index];
        const bool lower = edge_corners[cv.index][0] == cv.corner;
        voxel = corners[cv.corner];
        key = (std::uint64_t{voxel} * 6 + static_cast<std::uint64_t>(2 * axis + (lower ? 1 : 0))) << 2;
        break;
    }
    case CubeVertex::Kind::face_centre: {
        // Shared by the two cubes on either side: named by the face's lowest corner, and owned by
        // the smallest voxel slot among its four corners.
        const int axis = cv.index / 2, side = cv.index % 2;
        grid::Coord lowest = cube;
        lowest[axis] += side;
        voxel = grid::no_index;
        for (int c = 0; c < 8; ++c)
            if (((c >> axis) & 1) == side) voxel = std::min(voxel, corners[c]);
        key = ((morton(lowest - m_origin) * 3 + static_cast<std::uint64_t>(axis)) << 2) | 1;
        break;
    }
    case CubeVertex::Kind::cube_centre:
        voxel = corners[cv.corner];
        key = ((morton(cube - m_origin) * 128 + 8u * cv.index + cv.corner) << 2) | 2;
        break;
    }

    const std::uint32_t found = m_vertex_index.find(key);
    if (found != grid::CoordMap::missing) {
        ++m_vertices[found].users;
        return found;
    }
    std::uint32_t id;
    if (!m_free_vertices.empty()) {
        id = m_free_vertices.back();
        m_free_vertices.pop_back();
    } else {
        id = static_cast<std::uint32_t>(m_vertices.size());
        m_vertices.emplace_back();
        m_vertex_triangles.emplace_back();
        m_list_place.push_back(grid::no_index);
    }
    SurfaceVertex& v = m_vertices[id];
    const auto p = cube_vertex_position(cv);
    v.key = key;
    v.voxel = voxel;
    v.rest = cube.cast<double>() + Eigen::Vector3d(p[0], p[1], p[2]);
    v.label = grid.voxels().label(voxel);
    v.users = 1;
    ++m_owned[voxel];
    place(grid, id);
    m_vertex_index.insert(key, id);
    if (cv.kind != CubeVertex::Kind::crossing) m_centre_vertices.emplace(voxel, id);
    ++m_vertex_count;
    return id;
}

void EmbeddedSurface::embed(const grid::BranchedGrid& grid, SurfaceVertex& v) const
{
    v.element = grid.element_of(v.voxel, m_level);
    const grid::Coord& cell = grid.level(m_level).elements[v.element].cell;
    v.local = (v.rest - grid::BranchedGrid::cell_corner_index(cell, m_level, 0)) / static_cast<double>(1 << m_level);
}

void EmbeddedSurface::reembed(const grid::BranchedGrid& grid, int level)
{
    m_level = level;
    m_element_vertices.clear();
    std::fill(m_list_place.begin(), m_list_place.end(), grid::no_index);
    for (std::uint32_t v = 0; v < m_vertices.size(); ++v)
        if (m_vertices[v].users) place(grid, v);
}

void EmbeddedSurface::unlist(std::uint32_t v)
{
    const std::uint32_t at = m_list_place[v];
    if (at == grid::no_index) return;
    std::vector<std::uint32_t>& list = m_element_vertices[m_vertices[v].element];
    m_list_place[list.back()] = at; // the last one takes its place
    list[at] = list.back();
    list.pop_back();
    m_list_place[v] = grid::no_index;
}

void EmbeddedSurface::place(const grid::BranchedGrid& grid, std::uint32_t v)
{
    unlist(v);
    SurfaceVertex& vertex = m_vertices[v];
    embed(grid, vertex);
    if (m_element_vertices.size() <= vertex.element) m_element_vertices.resize(grid.level(m_level).elements.size());
    std::vector<std::uint32_t>& list = m_element_vertices[vertex.element];
    m_list_place[v] = static_cast<std::uint32_t>(list.size());
    list.push_back(v);
}

void EmbeddedSurface::release_vertex(std::uint32_t id)
{
    SurfaceVertex& v = m_vertices[id];
    if (--v.users > 0) return;
    unlist(id);
    m_vertex_index.insert(v.key, grid::CoordMap::missing);
    --m_owned[v.voxel];
    if ((v.key & 3) != 0) {
        auto [first, last] = m_centre_vertices.equal_range(v.voxel);
        for (auto it = first; it != last; ++it)
            if (it->second == id) {
                m_centre_vertices.erase(it);
                break;
            }
    }
    m_free_vertices.push_back(id);
    --m_vertex_count;
}

void EmbeddedSurface::update(const grid::BranchedGrid& grid, std::span<const grid::Coord> removed,
                             std::span<const std::pair<grid::Coord, int>> faces, const grid::UpdateReport& report)
{
    // The cubes touching a removed voxel (8) or a disconnected face's edge (4).
    std::vector<grid::Coord> cubes;
    for (const grid::Coord& c : removed)
        for (int k = 0; k < 8; ++k) cubes.push_back(c - corner_offset(k));
    for (const auto& [c, axis] : faces) {
        const int u = (axis + 1) % 3, w = (axis + 2) % 3;
        for (int k = 0; k < 4; ++k) {
            grid::Coord m = c;
            m[u] -= k & 1;
            m[w] -= (k >> 1) & 1;
            cubes.push_back(m);
        }
    }
    std::sort(cubes.begin(), cubes.end(), [](const grid::Coord& a, const grid::Coord& b) {
        return std::lexicographical_compare(a.begin(), a.end(), b.begin(), b.end());
    });
    cubes.erase(std::unique(cubes.begin(), cubes.end()), cubes.end());
    for (const grid::Coord& cube : cubes) extract_cube(grid, cube);

    // Vertices of voxels that now belong to a new element are embedded again.
    if (report.levels.size() <= static_cast<std::size_t>(m_level)) return;
    for (const auto& [element, from] : report.levels[static_cast<std::size_t>(m_level)].created)
        for (std::uint32_t voxel : grid.level(m_level).elements[element].voxels) {
            if (m_owned[voxel] == 0) continue; // most voxels of an element hold no surface vertex
            for (std::uint64_t dir = 0; dir < 6; ++dir) {
                const std::uint32_t id = m_vertex_index.find((std::uint64_t{voxel} * 6 + dir) << 2);
                if (id != grid::CoordMap::missing) place(grid, id);
            }
            auto [first, last] = m_centre_vertices.equal_range(voxel);
            for (auto it = first; it != last; ++it) place(grid, it->second);
        }
}

void EmbeddedSurface::deform(const grid::BranchedGrid& grid, std::span<const Eigen::Vector3d> nodes,
                             std::vector<Eigen::Vector3d>& out) const
{
    out.resize(m_vertices.size());
    const auto& elements = grid.level(m_level).elements;
    for (std::size_t i = 0; i < m_vertices.size(); ++i) {
        const SurfaceVertex& v = m_vertices[i];
        if (v.users == 0) continue;
        const auto& n = elements[v.element].nodes;
        const Eigen::Vector3d t = v.local, s = Eigen::Vector3d::Ones() - v.local;
        // Trilinear interpolation, factored along x, then y, then z.
        const Eigen::Vector3d x00 = s.x() * nodes[n[0]] + t.x() * nodes[n[1]];
        const Eigen::Vector3d x10 = s.x() * nodes[n[2]] + t.x() * nodes[n[3]];
        const Eigen::Vector3d x01 = s.x() * nodes[n[4]] + t.x() * nodes[n[5]];
        const Eigen::Vector3d x11 = s.x() * nodes[n[6]] + t.x() * nodes[n[7]];
        out[i] = s.z() * (s.y() * x00 + t.y() * x10) + t.z() * (s.y() * x01 + t.y() * x11);
    }
}

SurfaceMesh EmbeddedSurface::mesh(const grid::BranchedGrid& grid) const
{
    std::vector<Eigen::Vector3d> world(m_vertices.size());
    for (std::size_t i = 0; i < m_vertices.size(); ++i)
        if (m_vertices[i].users) world[i] = grid.voxels().world_mm(m_vertices[i].rest);
    SurfaceMesh out;
    std::vector<std::uint32_t> compact(m_vertices.size(), grid::no_index);
    for (std::size_t i = 0; i < m_vertices.size(); ++i)
        if (m_vertices[i].users) {
            compact[i] = static_cast<std::uint32_t>(out.positions.size());
            out.positions.push_back(world[i]);
            out.labels.push_back(m_vertices[i].label);
        }
    out.triangles.reserve(m_triangle_count);
    for (const auto& tri : m_triangles) {
        if (tri[0] == grid::no_index) continue;
        Eigen::Vector3i t3(static_cast<int>(compact[tri[0]]), static_cast<int>(compact[tri[1]]), static_cast<int>(compact[tri[2]]));
        if (m_flip) std::swap(t3[1], t3[2]);
        out.triangles.push_back(t3);
    }
    return out;
}

SurfaceMesh EmbeddedSurface::mesh(const grid::BranchedGrid& grid, std::span<const Eigen::Vector3d> nodes) const
{
    SurfaceMesh out = mesh(grid);
    std::vector<Eigen::Vector3d> deformed;
    deform(grid, nodes, deformed);
    std::size_t k = 0;
    for (std::size_t i = 0; i < m_vertices.size(); ++i)
        if (m_vertices[i].users) out.positions[k++] = deformed[i];
    return out;
}

std::vector<std::vector<std::uint32_t>> EmbeddedSurface::vertex_neighbours() const
{
    std::vector<std::vector<std::uint32_t>> neighbours(m_vertices.size());
    for (const auto& tri : m_triangles) {
        if (tri[0] == grid::no_index) continue;
        for (int k = 0; k < 3; ++k) {
            neighbours[tri[k]].push_back(tri[(k + 1) % 3]);
            neighbours[tri[k]].push_back(tri[(k + 2) % 3]);
        }
    }
    for (auto& n : neighbours) {
        std::sort(n.begin(), n.end());
        n.erase(std::unique(n.begin(), n.end()), n.end());
    }
    return neighbours;
}

void EmbeddedSurface::set_rest_world(const grid::BranchedGrid& grid, const std::vector<Eigen::Vector3d>& x)
{
    const Eigen::Matrix3d inverse = grid.voxels().index_to_world().topLeftCorner<3, 3>().inverse();
    const Eigen::Vector3d size = Eigen::Vector3d::Constant(static_cast<double>(1 << m_level));
    for (std::size_t i = 0; i < m_vertices.size(); ++i) {
        SurfaceVertex& v = m_vertices[i];
        if (v.users == 0) continue;
        v.rest = inverse * x[i];
        // Same element; coordinates may leave [0, 1] slightly, which trilinear interpolation allows.
        const grid::Coord& cell = grid.level(m_level).elements[v.element].cell;
        v.local = (v.rest - grid::BranchedGrid::cell_corner_index(cell, m_level, 0)).cwiseQuotient(size);
    }
}

void EmbeddedSurface::smooth(const grid::BranchedGrid& grid, int iterations)
{
    const Eigen::Matrix3d linear = grid.voxels().index_to_world().topLeftCorner<3, 3>();
    const std::vector<std::vector<std::uint32_t>> neighbours = vertex_neighbours();
    // Taubin's lambda|mu filter in world space (anisotropic voxels must not bias it).
    std::vector<Eigen::Vector3d> x(m_vertices.size()), next(m_vertices.size());
    for (std::size_t i = 0; i < m_vertices.size(); ++i) x[i] = linear * m_vertices[i].rest;
    Progress progress("smoothing the surface", static_cast<std::uint64_t>(2 * iterations));
    for (int it = 0; it < 2 * iterations; ++it) {
        progress.update(static_cast<std::uint64_t>(it));
        const double factor = it % 2 == 0 ? 0.5 : -0.53;
        for (std::size_t i = 0; i < x.size(); ++i) {
            next[i] = x[i];
            if (m_vertices[i].users == 0 || neighbours[i].empty()) continue;
            Eigen::Vector3d mean = Eigen::Vector3d::Zero();
            for (std::uint32_t j : neighbours[i]) mean += x[j];
            next[i] += factor * (mean / static_cast<double>(neighbours[i].size()) - x[i]);
        }
        std::swap(x, next);
    }
    set_rest_world(grid, x);
}

namespace {

/// Enclosed volume (world units cubed) of the used triangles over points `x`; `sign` -1 when the
/// corner order gives inward normals.
double enclosed_volume(const std::vector<std::array<std::uint32_t, 3>>& triangles, const std::vector<Eigen::Vector3d>& x,
                       double sign)
{
    double six_v = 0.0;
    for (const auto& t : triangles)
        if (t[0] != grid::no_index) six_v += x[t[0]].dot(x[t[1]].cross(x[t[2]]));
    return sign * six_v / 6.0;
}

} // namespace

double EmbeddedSurface::rest_volume_mm3(const grid::BranchedGrid& grid) const
{
    const Eigen::Matrix3d linear = grid.voxels().index_to_world().topLeftCorner<3, 3>();
    std::vector<Eigen::Vector3d> x(m_vertices.size());
    for (std::size_t i = 0; i < m_vertices.size(); ++i) x[i] = linear * m_vertices[i].rest;
    return enclosed_volume(m_triangles, x, m_flip ? -1.0 : 1.0);
}

double EmbeddedSurface::smooth_windowed_sinc(const grid::BranchedGrid& grid, int iterations, double passband)
{
    if (iterations < 1 || !(passband > 0.0 && passband < 2.0))
        throw std::invalid_argument("smooth_windowed_sinc: iterations >= 1 and passband in (0, 2)");
    const Eigen::Matrix3d linear = grid.voxels().index_to_world().topLeftCorner<3, 3>();
    const std::vector<std::vector<std::uint32_t>> neighbours = vertex_neighbours();
    const std::size_t n = m_vertices.size();
    const double sign = m_flip ? -1.0 : 1.0;
    // The neighbour average W has eigenvalues cos(theta) in [-1, 1] (theta the mesh frequency);
    // the ideal low pass 1 for theta < theta_pb has cosine coefficients c_0 = theta_pb / pi,
    // c_i = 2 sin(i theta_pb) / (i pi); cos(i theta) = T_i(cos theta) is the Chebyshev polynomial
    // of W, so the filter is sum_i w_i c_i T_i(W) x (w: a Hamming window), normalised to pass
    // theta = 0 (the shape's mean) exactly. passband is 1 - cos(theta_pb), as the eigenvalues of
    // I - W (VTK's vtkWindowedSincPolyDataFilter maps it the same way up to a factor of 2).
    const double theta = std::acos(1.0 - passband);
    const double pi = 3.14159265358979323846;
    std::vector<double> weight(static_cast<std::size_t>(iterations) + 1);
    double sum = 0.0;
    for (int i = 0; i <= iterations; ++i) {
        const double c = i == 0 ? theta / pi : 2.0 * std::sin(i * theta) / (i * pi);
        const double window = 0.54 + 0.46 * std::cos(i * pi / (iterations + 1));
        weight[static_cast<std::size_t>(i)] = c * window;
        sum += c * window;
    }
    for (double& w : weight) w /= sum;

    std::vector<Eigen::Vector3d> t0(n), t1(n), t2(n), out(n);
    for (std::size_t i = 0; i < n; ++i) t0[i] = linear * m_vertices[i].rest;
    const double volume_before = enclosed_volume(m_triangles, t0, sign);
    auto average = [&](const std::vector<Eigen::Vector3d>& x, std::size_t i) {
        if (m_vertices[i].users == 0 || neighbours[i].empty()) return x[i];
        Eigen::Vector3d mean = Eigen::Vector3d::Zero();
        for (std::uint32_t j : neighbours[i]) mean += x[j];
        return Eigen::Vector3d(mean / static_cast<double>(neighbours[i].size()));
    };
    Progress progress("smoothing the surface", static_cast<std::uint64_t>(iterations));
    for (std::size_t i = 0; i < n; ++i) {
        t1[i] = average(t0, i);
        out[i] = weight[0] * t0[i] + weight[1] * t1[i];
    }
    for (int k = 2; k <= iterations; ++k) {
        progress.update(static_cast<std::uint64_t>(k));
        for (std::size_t i = 0; i < n; ++i) {
            t2[i] = 2.0 * average(t1, i) - t0[i];
            out[i] += weight[static_cast<std::size_t>(k)] * t2[i];
        }
        std::swap(t0, t1);
        std::swap(t1, t2);
    }
    const double volume_smoothed = enclosed_volume(m_triangles, out, sign);
    // Restore the volume: move every vertex by the same distance along its normal (two passes,
    // as the area changes a little with the move).
    for (int pass = 0; pass < 2; ++pass) {
        std::vector<Eigen::Vector3d> normal(n, Eigen::Vector3d::Zero());
        double area = 0.0;
        for (const auto& t : m_triangles) {
            if (t[0] == grid::no_index) continue;
            const Eigen::Vector3d twice = sign * (out[t[1]] - out[t[0]]).cross(out[t[2]] - out[t[0]]);
            area += 0.5 * twice.norm();
            for (int c = 0; c < 3; ++c) normal[t[static_cast<std::size_t>(c)]] += twice;
        }
        const double volume = enclosed_volume(m_triangles, out, sign);
        if (area <= 0.0) break;
        const double shift = (volume_before - volume) / area;
        for (std::size_t i = 0; i < n; ++i)
            if (m_vertices[i].users > 0 && normal[i].squaredNorm() > 0.0) out[i] += shift * normal[i].normalized();
    }
    set_rest_world(grid, out);
    return volume_before != 0.0 ? volume_smoothed / volume_before - 1.0 : 0.0;
}

} // namespace vox::surface
