#include "isxfem/polygon_triangulation.hpp"

#include <algorithm>
#include <numeric>

namespace vox::isxfem {
namespace {

double cross(const Eigen::Vector2d& a, const Eigen::Vector2d& b, const Eigen::Vector2d& c)
{
    return (b - a).x() * (c - a).y() - (b - a).y() * (c - a).x();
}

/// Whether segments ab and cd cross at a point inside both (touching ends do not count).
bool crosses(const Eigen::Vector2d& a, const Eigen::Vector2d& b, const Eigen::Vector2d& c, const Eigen::Vector2d& d)
{
    auto side = [](const Eigen::Vector2d& p, const Eigen::Vector2d& q, const Eigen::Vector2d& r) {
        const double z = cross(p, q, r);
        return (z > 0.0) - (z < 0.0);
    };
    return side(a, b, c) * side(a, b, d) < 0 && side(c, d, a) * side(c, d, b) < 0;
}

bool inside_polygon(const Eigen::Vector2d& p, const std::vector<Eigen::Vector2d>& polygon)
{
    bool in = false;
    for (std::size_t i = 0, j = polygon.size() - 1; i < polygon.size(); j = i++)
        if ((polygon[i].y() > p.y()) != (polygon[j].y() > p.y()) &&
            p.x() < polygon[j].x() + (p.y() - polygon[j].y()) / (polygon[i].y() - polygon[j].y()) * (polygon[i].x() - polygon[j].x()))
            in = !in;
    return in;
}

double signed_area(const std::vector<Eigen::Vector2d>& polygon)
{
    double a = 0.0;
    for (std::size_t i = 0; i < polygon.size(); ++i) {
        const Eigen::Vector2d& p = polygon[i];
        const Eigen::Vector2d& q = polygon[(i + 1) % polygon.size()];
        a += 0.5 * (p.x() * q.y() - q.x() * p.y());
    }
    return a;
}

std::size_t rightmost(const std::vector<Eigen::Vector2d>& polygon)
{
    return static_cast<std::size_t>(
        std::max_element(polygon.begin(), polygon.end(), [](const Eigen::Vector2d& p, const Eigen::Vector2d& q) { return p.x() < q.x(); }) -
        polygon.begin());
}

bool inside_triangle(const Eigen::Vector2d& p, const Eigen::Vector2d& a, const Eigen::Vector2d& b, const Eigen::Vector2d& c)
{
    return cross(a, b, p) >= 0.0 && cross(b, c, p) >= 0.0 && cross(c, a, p) >= 0.0;
}

} // namespace

std::vector<std::array<int, 3>> triangulate_polygon(const std::vector<Eigen::Vector2d>& polygon, const std::vector<bool>& apart)
{
    std::vector<std::array<int, 3>> out;
    const int n = static_cast<int>(polygon.size());
    if (n < 3) return out;
    std::vector<int> v(static_cast<std::size_t>(n));
    std::iota(v.begin(), v.end(), 0);
    if (signed_area(polygon) < 0.0) std::reverse(v.begin(), v.end()); // work counter-clockwise
    auto at = [&](int i) -> const Eigen::Vector2d& { return polygon[static_cast<std::size_t>(v[static_cast<std::size_t>(i)])]; };
    auto flagged = [&](int i) { return !apart.empty() && apart[static_cast<std::size_t>(v[static_cast<std::size_t>(i)])]; };
    // The first ear (its tip's place in v), or -1; `avoiding`: none whose diagonal joins two
    // flagged vertices.
    auto find_ear = [&](bool avoiding) {
        const int m = static_cast<int>(v.size());
        for (int i = 0; i < m; ++i) {
            const int prev = (i + m - 1) % m, next = (i + 1) % m;
            if (cross(at(prev), at(i), at(next)) <= 0.0) continue; // reflex or flat
            if (avoiding && flagged(prev) && flagged(next)) continue;
            bool empty = true;
            for (int j = 0; j < m && empty; ++j)
                if (j != prev && j != i && j != next && at(j) != at(prev) && at(j) != at(i) && at(j) != at(next))
                    empty = !inside_triangle(at(j), at(prev), at(i), at(next));
            if (empty) return i;
        }
        return -1;
    };
    while (v.size() > 3) {
        int i = find_ear(!apart.empty());
        if (i < 0 && !apart.empty()) i = find_ear(false);
        if (i < 0) { // not simple (or degenerate): fan over what is left
            for (std::size_t k = 1; k + 1 < v.size(); ++k) out.push_back({v[0], v[k], v[k + 1]});
            return out;
        }
        const int m = static_cast<int>(v.size());
        out.push_back({v[static_cast<std::size_t>((i + m - 1) % m)], v[static_cast<std::size_t>(i)], v[static_cast<std::size_t>((i + 1) % m)]});
        v.erase(v.begin() + i);
    }
    out.push_back({v[0], v[1], v[2]});
    return out;
}

Location locate(const std::vector<Eigen::Vector2d>& points, const std::vector<std::array<int, 3>>& triangles, const Eigen::Vector2d& p)
{
    auto at = [&](int i) -> const Eigen::Vector2d& { return points[static_cast<std::size_t>(i)]; };
    for (std::size_t k = 0; k < triangles.size(); ++k) {
        const std::array<int, 3>& t = triangles[k];
        if (!(cross(at(t[0]), at(t[1]), at(t[2])) > 0.0)) continue;
        // Distances to the edges (positive inside), against a hundredth of the longest edge: a
        // point nearer than that to an edge lies on it (split there, not beside it: a nearly flat
        // triangle would be left).
        double longest = 0.0;
        std::array<double, 3> distance{};
        for (std::size_t e = 0; e < 3; ++e) {
            const Eigen::Vector2d& a = at(t[e]);
            const Eigen::Vector2d& b = at(t[(e + 1) % 3]);
            longest = std::max(longest, (b - a).norm());
            distance[e] = cross(a, b, p) / (b - a).norm();
        }
        const double tolerance = 1e-2 * longest;
        int on = -1, clear = 0;
        for (std::size_t e = 0; e < 3; ++e) {
            if (distance[e] > tolerance) ++clear;
            else if (distance[e] >= -tolerance) on = static_cast<int>(e);
        }
        if (clear == 3) return {static_cast<int>(k), -1};
        if (clear == 2 && on >= 0) {
            const int u = t[static_cast<std::size_t>(on)], v = t[static_cast<std::size_t>((on + 1) % 3)], w = t[static_cast<std::size_t>((on + 2) % 3)];
            for (std::size_t j = 0; j < triangles.size(); ++j)
                for (std::size_t e = 0; e < 3; ++e)
                    if (triangles[j][e] == v && triangles[j][(e + 1) % 3] == u) {
                        // The four triangles the split makes must all face the same way: p just
                        // beyond the edge of a thin triangle across could turn one over.
                        const int z = triangles[j][(e + 2) % 3];
                        const bool turns = cross(at(w), at(u), p) <= 0.0 || cross(at(v), at(w), p) <= 0.0 || cross(at(z), at(v), p) <= 0.0 ||
                                           cross(at(u), at(z), p) <= 0.0;
                        return turns ? Location{} : Location{static_cast<int>(k), on, static_cast<int>(j)};
                    }
            return {}; // on the polygon's boundary: not inside
        }
    }
    return {};
}

void insert_point(std::vector<Eigen::Vector2d>& points, std::vector<std::array<int, 3>>& triangles, const Location& where,
                  const Eigen::Vector2d& p, std::size_t boundary)
{
    const int id = static_cast<int>(points.size());
    points.push_back(p);
    const std::array<int, 3> split = triangles[static_cast<std::size_t>(where.triangle)];
    // The edges opposite p, each with a triangle (a, b, p) on its left.
    std::vector<std::pair<int, int>> edges;
    if (where.edge < 0) { // inside: three triangles
        triangles[static_cast<std::size_t>(where.triangle)] = {split[0], split[1], id};
        triangles.push_back({split[1], split[2], id});
        triangles.push_back({split[2], split[0], id});
        edges = {{split[0], split[1]}, {split[1], split[2]}, {split[2], split[0]}};
    } else { // on the edge u-v: it and the triangle across it, two each
        const auto e = static_cast<std::size_t>(where.edge);
        const int u = split[e], v = split[(e + 1) % 3], w = split[(e + 2) % 3];
        const auto across = static_cast<std::size_t>(where.across);
        const std::array<int, 3>& other = triangles[across];
        const int z = other[0] != u && other[0] != v ? other[0] : other[1] != u && other[1] != v ? other[1] : other[2];
        triangles[static_cast<std::size_t>(where.triangle)] = {w, u, id};
        triangles.push_back({v, w, id});
        triangles[across] = {z, v, id};
        triangles.push_back({u, z, id});
        edges = {{w, u}, {v, w}, {z, v}, {u, z}};
    }
    auto at = [&](int i) -> const Eigen::Vector2d& { return points[static_cast<std::size_t>(i)]; };
    auto fixed = [&](int a, int b) {
        const auto n = static_cast<int>(boundary);
        return a < n && b < n && ((a + 1) % n == b || (b + 1) % n == a);
    };
    // Each triangle (a, b, id) holds p; its edge a-b is flipped when the point across it lies in
    // its circumcircle, and the two new edges opposite p are checked in turn.
    while (!edges.empty()) {
        const auto [a, b] = edges.back();
        edges.pop_back();
        if (fixed(a, b)) continue;
        std::size_t mine = triangles.size(), across = triangles.size();
        int d = -1;
        for (std::size_t k = 0; k < triangles.size(); ++k)
            for (std::size_t e = 0; e < 3; ++e) {
                const int u = triangles[k][e], v = triangles[k][(e + 1) % 3];
                if (u == a && v == b && triangles[k][(e + 2) % 3] == id) mine = k;
                if (u == b && v == a) {
                    across = k;
                    d = triangles[k][(e + 2) % 3];
                }
            }
        if (mine == triangles.size() || across == triangles.size()) continue;
        const Eigen::Vector2d pa = at(a) - at(d), pb = at(b) - at(d), pp = at(id) - at(d);
        const double in_circle = pa.squaredNorm() * (pb.x() * pp.y() - pb.y() * pp.x()) - pb.squaredNorm() * (pa.x() * pp.y() - pa.y() * pp.x()) +
                                 pp.squaredNorm() * (pa.x() * pb.y() - pa.y() * pb.x());
        if (!(in_circle > 0.0) || cross(at(a), at(d), at(id)) <= 0.0 || cross(at(d), at(b), at(id)) <= 0.0) continue;
        triangles[mine] = {a, d, id};
        triangles[across] = {d, b, id};
        edges.emplace_back(a, d);
        edges.emplace_back(d, b);
    }
}

std::vector<std::vector<LoopCorner>> faces_with_holes(const std::vector<std::vector<Eigen::Vector2d>>& loops, std::size_t& left_out)
{
    std::vector<double> area;
    for (const auto& loop : loops) area.push_back(signed_area(loop));
    std::vector<std::vector<std::size_t>> holes(loops.size());
    for (std::size_t h = 0; h < loops.size(); ++h) {
        if (area[h] >= 0.0 || loops[h].empty()) continue;
        std::size_t around = loops.size();
        for (std::size_t o = 0; o < loops.size(); ++o)
            if (area[o] > 0.0 && inside_polygon(loops[h].front(), loops[o]) && (around == loops.size() || area[o] < area[around])) around = o;
        if (around == loops.size())
            ++left_out; // a hole in nothing
        else
            holes[around].push_back(h);
    }
    std::vector<std::vector<LoopCorner>> faces;
    for (std::size_t o = 0; o < loops.size(); ++o) {
        if (area[o] <= 0.0) continue;
        std::vector<LoopCorner> face;
        std::vector<Eigen::Vector2d> points = loops[o];
        for (std::size_t c = 0; c < points.size(); ++c) face.push_back({o, c});
        std::sort(holes[o].begin(), holes[o].end(), [&](std::size_t a, std::size_t b) {
            return loops[a][rightmost(loops[a])].x() > loops[b][rightmost(loops[b])].x();
        });
        for (std::size_t h : holes[o]) {
            const std::vector<Eigen::Vector2d>& hole = loops[h];
            const std::size_t m = rightmost(hole);
            auto blocked_by = [&](const std::vector<Eigen::Vector2d>& poly, const Eigen::Vector2d& to) {
                for (std::size_t i = 0; i < poly.size(); ++i)
                    if (crosses(hole[m], to, poly[i], poly[(i + 1) % poly.size()])) return true;
                return false;
            };
            std::vector<std::size_t> order(points.size());
            for (std::size_t i = 0; i < order.size(); ++i) order[i] = i;
            std::sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) {
                return (points[a] - hole[m]).squaredNorm() < (points[b] - hole[m]).squaredNorm();
            });
            const auto v = std::find_if(order.begin(), order.end(), [&](std::size_t i) {
                return !blocked_by(points, points[i]) &&
                       std::none_of(holes[o].begin(), holes[o].end(), [&](std::size_t other) { return blocked_by(loops[other], points[i]); });
            });
            if (v == order.end()) {
                ++left_out; // no bridge
                continue;
            }
            // face[..v], hole[m..] round to hole[m], face[v..]
            std::vector<LoopCorner> merged(face.begin(), face.begin() + static_cast<std::ptrdiff_t>(*v + 1));
            std::vector<Eigen::Vector2d> merged_points(points.begin(), points.begin() + static_cast<std::ptrdiff_t>(*v + 1));
            for (std::size_t k = 0; k <= hole.size(); ++k) {
                merged.push_back({h, (m + k) % hole.size()});
                merged_points.push_back(hole[(m + k) % hole.size()]);
            }
            merged.insert(merged.end(), face.begin() + static_cast<std::ptrdiff_t>(*v), face.end());
            merged_points.insert(merged_points.end(), points.begin() + static_cast<std::ptrdiff_t>(*v), points.end());
            face = std::move(merged);
            points = std::move(merged_points);
        }
        faces.push_back(std::move(face));
    }
    return faces;
}

} // namespace vox::isxfem
