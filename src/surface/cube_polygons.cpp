#include "surface/cube_polygons.hpp"

#include <algorithm>
#include <tuple>

namespace vox::surface {
namespace {

using Vec = std::array<double, 3>;

Vec corner_position(int c) { return {double(c & 1), double((c >> 1) & 1), double((c >> 2) & 1)}; }
Vec sub(const Vec& a, const Vec& b) { return {a[0] - b[0], a[1] - b[1], a[2] - b[2]}; }
Vec mid(const Vec& a, const Vec& b) { return {0.5 * (a[0] + b[0]), 0.5 * (a[1] + b[1]), 0.5 * (a[2] + b[2])}; }
double triple(const Vec& d, const Vec& u, const Vec& n)
{
    const Vec c{d[1] * u[2] - d[2] * u[1], d[2] * u[0] - d[0] * u[2], d[0] * u[1] - d[1] * u[0]};
    return c[0] * n[0] + c[1] * n[1] + c[2] * n[2];
}

int edge_between(int a, int b)
{
    for (int e = 0; e < 12; ++e)
        if ((edge_corners[e][0] == a && edge_corners[e][1] == b) || (edge_corners[e][0] == b && edge_corners[e][1] == a))
            return e;
    return -1;
}

CubeVertex crossing(int corner, int edge)
{
    return {CubeVertex::Kind::crossing, static_cast<std::uint8_t>(corner), static_cast<std::uint8_t>(edge)};
}

auto vertex_order(const CubeVertex& v) { return std::tuple(static_cast<int>(v.kind), v.corner, v.index); }

struct Segment {
    std::vector<CubeVertex> vertices; ///< first and last are crossings; a face centre may sit between
    int component = 0;
    int face = 0;
};

} // namespace

std::array<double, 3> cube_vertex_position(const CubeVertex& v)
{
    switch (v.kind) {
    case CubeVertex::Kind::crossing:
        return mid(corner_position(edge_corners[v.index][0]), corner_position(edge_corners[v.index][1]));
    case CubeVertex::Kind::face_centre: {
        Vec p{0.5, 0.5, 0.5};
        p[static_cast<std::size_t>(v.index / 2)] = v.index % 2;
        return p;
    }
    case CubeVertex::Kind::cube_centre: break;
    }
    return {0.5, 0.5, 0.5};
}

std::vector<CubeLoop> polygonise_cube(std::uint8_t present, std::uint16_t connected)
{
    auto is_present = [&](int c) { return (present >> c) & 1; };
    auto joined = [&](int e) {
        return is_present(edge_corners[e][0]) && is_present(edge_corners[e][1]) && ((connected >> e) & 1);
    };

    // Components of the present corners through joined edges (smallest corner as the label).
    std::array<int, 8> component{};
    for (int c = 0; c < 8; ++c) component[c] = c;
    for (bool changed = true; changed;) {
        changed = false;
        for (int e = 0; e < 12; ++e) {
            if (!joined(e)) continue;
            int& a = component[edge_corners[e][0]];
            int& b = component[edge_corners[e][1]];
            if (a != b) {
                a = b = std::min(a, b);
                changed = true;
            }
        }
    }

    // Boundary segments of every face, decided from the face alone.
    std::vector<Segment> segments;
    for (int axis = 0; axis < 3; ++axis)
        for (int side = 0; side < 2; ++side) {
            const int u = (axis + 1) % 3, v = (axis + 2) % 3;
            const int base = side << axis;
            const std::array<int, 4> q{base, base | 1 << u, base | 1 << u | 1 << v, base | 1 << v};
            std::array<int, 4> fe{};
            std::array<bool, 4> link{};
            int present_count = 0, breaks = 0;
            for (int i = 0; i < 4; ++i) {
                fe[i] = edge_between(q[i], q[(i + 1) % 4]);
                link[i] = joined(fe[i]);
                present_count += is_present(q[i]);
                breaks += !link[i];
            }
            Vec normal{0, 0, 0};
            normal[axis] = side ? 1.0 : -1.0;
            const int face = 2 * axis + side;

            if (present_count == 4 && breaks == 0) continue; // material across the whole face
            if (present_count == 4 && breaks == 1) {
                // The end of a cut: around the wall's tip through the face centre.
                const int i = static_cast<int>(std::find(link.begin(), link.end(), false) - link.begin());
                const CubeVertex a = crossing(q[i], fe[i]), b = crossing(q[(i + 1) % 4], fe[i]);
                const CubeVertex f{CubeVertex::Kind::face_centre, static_cast<std::uint8_t>(q[i]),
                                   static_cast<std::uint8_t>(face)};
                const Vec pa = cube_vertex_position(a), pf = cube_vertex_position(f);
                Segment s{{a, f, b}, component[q[i]], face};
                if (triple(sub(pf, pa), sub(corner_position(q[i]), mid(pa, pf)), normal) > 0)
                    std::reverse(s.vertices.begin(), s.vertices.end());
                segments.push_back(std::move(s));
                continue;
            }
            // Arcs of present corners joined around the face, each cut off by a chamfer between the
            // crossings on the edges to its predecessor and successor.
            const int start = static_cast<int>(std::find(link.begin(), link.end(), false) - link.begin()) + 1;
            for (int k = 0; k < 4;) {
                const int first = (start + k) % 4;
                if (!is_present(q[first])) {
                    ++k;
                    continue;
                }
                int last = first, length = 1;
                while (link[last] && k + length < 4) {
                    last = (last + 1) % 4;
                    ++length;
                }
                const CubeVertex a = crossing(q[first], fe[(first + 3) % 4]);
                const CubeVertex b = crossing(q[last], fe[last]);
                Vec centroid{0, 0, 0};
                for (int j = 0; j < length; ++j) {
                    const Vec p = corner_position(q[(first + j) % 4]);
                    for (int d = 0; d < 3; ++d) centroid[d] += p[d] / length;
                }
                const Vec pa = cube_vertex_position(a), pb = cube_vertex_position(b);
                Segment s{{a, b}, component[q[first]], face};
                if (triple(sub(pb, pa), sub(centroid, mid(pa, pb)), normal) > 0)
                    std::reverse(s.vertices.begin(), s.vertices.end());
                segments.push_back(std::move(s));
                k += length;
            }
        }

    // Chain each component's segments into loops, starting from the smallest vertex.
    std::vector<CubeLoop> loops;
    std::vector<bool> used(segments.size(), false);
    for (;;) {
        int first = -1;
        for (std::size_t i = 0; i < segments.size(); ++i)
            if (!used[i] && (first < 0 || std::tuple(segments[i].component, vertex_order(segments[i].vertices.front())) <
                                              std::tuple(segments[static_cast<std::size_t>(first)].component,
                                                         vertex_order(segments[static_cast<std::size_t>(first)].vertices.front()))))
                first = static_cast<int>(i);
        if (first < 0) break;
        CubeLoop loop;
        CubeVertex last_end{};
        std::array<int, 6> per_face{};
        int current = first;
        while (current >= 0 && !used[static_cast<std::size_t>(current)]) {
            const Segment& s = segments[static_cast<std::size_t>(current)];
            used[static_cast<std::size_t>(current)] = true;
            last_end = s.vertices.back();
            // Two segments of one loop on the same face: a fan could lay a chord in that face, where
            // the neighbouring cube may lay the same one. A centre vertex keeps chords off faces.
            if (++per_face[static_cast<std::size_t>(s.face)] > 1) loop.needs_centre = true;
            for (std::size_t j = 0; j + 1 < s.vertices.size(); ++j) {
                loop.vertices.push_back(s.vertices[j]);
                loop.needs_centre = loop.needs_centre || s.vertices[j].kind == CubeVertex::Kind::face_centre;
            }
            current = -1;
            for (std::size_t i = 0; i < segments.size(); ++i)
                if (!used[i] && segments[i].component == s.component && segments[i].vertices.front() == s.vertices.back())
                    current = static_cast<int>(i);
        }
        if (!(segments[static_cast<std::size_t>(first)].vertices.front() == last_end)) loop.closed = false;
        loops.push_back(std::move(loop));
    }
    return loops;
}

CubeCase triangulate_cube(std::uint8_t present, std::uint16_t connected)
{
    CubeCase out;
    for (const CubeLoop& loop : polygonise_cube(present, connected)) {
        const auto& v = loop.vertices;
        if (loop.needs_centre) {
            const CubeVertex centre{CubeVertex::Kind::cube_centre, v[0].corner, v[0].index};
            for (std::size_t i = 0; i < v.size(); ++i) out.triangles.push_back({centre, v[i], v[(i + 1) % v.size()]});
        } else {
            for (std::size_t i = 1; i + 1 < v.size(); ++i) out.triangles.push_back({v[0], v[i], v[i + 1]});
        }
    }
    return out;
}

} // namespace vox::surface
