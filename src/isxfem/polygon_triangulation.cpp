#include "isxfem/polygon_triangulation.hpp"

#include <algorithm>
#include <numeric>

namespace vox::isxfem {
namespace {

double cross(const Eigen::Vector2d& a, const Eigen::Vector2d& b, const Eigen::Vector2d& c)
{
    return (b - a).x() * (c - a).y() - (b - a).y() * (c - a).x();
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
    double area = 0.0;
    for (int i = 0; i < n; ++i) {
        const Eigen::Vector2d& a = polygon[static_cast<std::size_t>(i)];
        const Eigen::Vector2d& b = polygon[static_cast<std::size_t>((i + 1) % n)];
        area += a.x() * b.y() - b.x() * a.y();
    }
    if (area < 0.0) std::reverse(v.begin(), v.end()); // work counter-clockwise
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

} // namespace vox::isxfem
