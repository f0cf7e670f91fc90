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

std::vector<std::array<int, 3>> triangulate_polygon(const std::vector<Eigen::Vector2d>& polygon)
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
    while (v.size() > 3) {
        const int m = static_cast<int>(v.size());
        bool clipped = false;
        for (int i = 0; i < m && !clipped; ++i) {
            const int prev = (i + m - 1) % m, next = (i + 1) % m;
            if (cross(at(prev), at(i), at(next)) <= 0.0) continue; // reflex or flat
            bool empty = true;
            for (int j = 0; j < m && empty; ++j)
                if (j != prev && j != i && j != next && at(j) != at(prev) && at(j) != at(i) && at(j) != at(next))
                    empty = !inside_triangle(at(j), at(prev), at(i), at(next));
            if (!empty) continue;
            out.push_back({v[static_cast<std::size_t>(prev)], v[static_cast<std::size_t>(i)], v[static_cast<std::size_t>(next)]});
            v.erase(v.begin() + i);
            clipped = true;
        }
        if (!clipped) { // not simple (or degenerate): fan over what is left
            for (std::size_t i = 1; i + 1 < v.size(); ++i) out.push_back({v[0], v[i], v[i + 1]});
            return out;
        }
    }
    out.push_back({v[0], v[1], v[2]});
    return out;
}

} // namespace vox::isxfem
