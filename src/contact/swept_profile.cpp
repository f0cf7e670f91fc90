#include "contact/swept_profile.hpp"

#include <algorithm>

namespace vox::contact {
namespace {

double cross(const Eigen::Vector2d& o, const Eigen::Vector2d& a, const Eigen::Vector2d& b)
{
    return (a.x() - o.x()) * (b.y() - o.y()) - (a.y() - o.y()) * (b.x() - o.x());
}

} // namespace

std::vector<Eigen::Vector2d> convex_hull(std::vector<Eigen::Vector2d> points)
{
    std::sort(points.begin(), points.end(), [](const Eigen::Vector2d& a, const Eigen::Vector2d& b) {
        return a.x() < b.x() || (a.x() == b.x() && a.y() < b.y());
    });
    points.erase(std::unique(points.begin(), points.end()), points.end());
    if (points.size() < 3) return points;
    std::vector<Eigen::Vector2d> hull(2 * points.size());
    std::size_t k = 0;
    for (const Eigen::Vector2d& p : points) { // lower chain
        while (k >= 2 && cross(hull[k - 2], hull[k - 1], p) <= 0.0) --k;
        hull[k++] = p;
    }
    for (std::size_t i = points.size() - 1, lower = k + 1; i-- > 0;) { // upper chain
        while (k >= lower && cross(hull[k - 2], hull[k - 1], points[i]) <= 0.0) --k;
        hull[k++] = points[i];
    }
    hull.resize(k - 1); // the last point repeats the first
    return hull;
}

SweptProfile::SweptProfile(std::vector<Eigen::Vector2d> profile) : m_profile(std::move(profile)) {}

void SweptProfile::add(const Eigen::Matrix2d& r0, const Eigen::Vector2d& t0, const Eigen::Matrix2d& r1, const Eigen::Vector2d& t1)
{
    std::vector<Eigen::Vector2d> placed;
    placed.reserve(2 * m_profile.size());
    for (const Eigen::Vector2d& p : m_profile) {
        placed.push_back(r0 * p + t0);
        placed.push_back(r1 * p + t1);
    }
    m_hulls.push_back(convex_hull(std::move(placed)));
}

bool SweptProfile::covers(const Eigen::Vector2d& q) const
{
    for (const auto& hull : m_hulls) {
        if (hull.size() < 3) continue;
        bool inside = true;
        for (std::size_t k = 0; k < hull.size() && inside; ++k) inside = cross(hull[k], hull[(k + 1) % hull.size()], q) >= 0.0;
        if (inside) return true;
    }
    return false;
}

} // namespace vox::contact
