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

int locate(const std::vector<Eigen::Vector2d>& points, const std::vector<std::array<int, 3>>& triangles, const Eigen::Vector2d& p)
{
    for (std::size_t k = 0; k < triangles.size(); ++k) {
        const Eigen::Vector2d& a = points[static_cast<std::size_t>(triangles[k][0])];
        const Eigen::Vector2d& b = points[static_cast<std::size_t>(triangles[k][1])];
        const Eigen::Vector2d& c = points[static_cast<std::size_t>(triangles[k][2])];
        // Clear of the edges by a millionth of the area: a point on an edge would leave a flat triangle.
        const double clear = 1e-6 * cross(a, b, c);
        if (clear > 0.0 && cross(a, b, p) > clear && cross(b, c, p) > clear && cross(c, a, p) > clear) return static_cast<int>(k);
    }
    return -1;
}

void insert_point(std::vector<Eigen::Vector2d>& points, std::vector<std::array<int, 3>>& triangles, int holder, const Eigen::Vector2d& p,
                  std::size_t boundary)
{
    const int id = static_cast<int>(points.size());
    points.push_back(p);
    const std::array<int, 3> split = triangles[static_cast<std::size_t>(holder)];
    triangles[static_cast<std::size_t>(holder)] = {split[0], split[1], id};
    triangles.push_back({split[1], split[2], id});
    triangles.push_back({split[2], split[0], id});
    auto at = [&](int i) -> const Eigen::Vector2d& { return points[static_cast<std::size_t>(i)]; };
    auto fixed = [&](int a, int b) {
        const auto n = static_cast<int>(boundary);
        return a < n && b < n && ((a + 1) % n == b || (b + 1) % n == a);
    };
    // Each triangle (a, b, id) holds p; its edge a-b is flipped when the point across it lies in
    // its circumcircle, and the two new edges opposite p are checked in turn.
    std::vector<std::pair<int, int>> edges{{split[0], split[1]}, {split[1], split[2]}, {split[2], split[0]}};
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
