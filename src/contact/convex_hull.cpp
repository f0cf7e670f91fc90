#include "contact/convex_hull.hpp"

#include <algorithm>

namespace vox::contact {
namespace {

double cross(const Eigen::Vector2d& o, const Eigen::Vector2d& a, const Eigen::Vector2d& b)
{
    return (a.x() - o.x()) * (b.y() - o.y()) - (a.y() - o.y()) * (b.x() - o.x());
}

} // namespace

std::size_t convex_hull(std::span<Eigen::Vector2d> points, std::span<Eigen::Vector2d> hull) noexcept
{
    std::sort(points.begin(), points.end(), [](const Eigen::Vector2d& a, const Eigen::Vector2d& b) {
        return a.x() < b.x() || (a.x() == b.x() && a.y() < b.y());
    });
    const auto n = static_cast<std::size_t>(std::unique(points.begin(), points.end()) - points.begin());
    if (n < 3) {
        std::copy_n(points.begin(), n, hull.begin());
        return n;
    }
    std::size_t k = 0;
    for (std::size_t i = 0; i < n; ++i) { // lower chain
        while (k >= 2 && cross(hull[k - 2], hull[k - 1], points[i]) <= 0.0) --k;
        hull[k++] = points[i];
    }
    for (std::size_t i = n - 1, lower = k + 1; i-- > 0;) { // upper chain
        while (k >= lower && cross(hull[k - 2], hull[k - 1], points[i]) <= 0.0) --k;
        hull[k++] = points[i];
    }
    return k - 1; // the last point repeats the first
}

std::vector<Eigen::Vector2d> convex_hull(std::vector<Eigen::Vector2d> points)
{
    std::vector<Eigen::Vector2d> hull(2 * points.size());
    hull.resize(convex_hull(std::span<Eigen::Vector2d>(points), std::span<Eigen::Vector2d>(hull)));
    return hull;
}

} // namespace vox::contact
