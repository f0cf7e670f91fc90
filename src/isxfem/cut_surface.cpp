#include "isxfem/cut_surface.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

namespace vox::isxfem {
namespace {

/// Squared distance from x to the segment a-b.
double segment_distance2(const Eigen::Vector3d& x, const Eigen::Vector3d& a, const Eigen::Vector3d& b)
{
    const Eigen::Vector3d ab = b - a;
    const double length2 = ab.squaredNorm();
    const double t = length2 > 0.0 ? std::clamp((x - a).dot(ab) / length2, 0.0, 1.0) : 0.0;
    return (a + t * ab - x).squaredNorm();
}

/// Whether x lies over the convex patch (its projection on the patch's plane inside it).
bool over(const Eigen::Vector3d& x, const CutPatch& p)
{
    for (std::size_t k = 0; k < p.corners.size(); ++k)
        if ((p.corners[(k + 1) % p.corners.size()] - p.corners[k]).cross(x - p.corners[k]).dot(p.normal) < 0.0) return false;
    return true;
}

/// Squared distance from x to a convex patch.
double patch_distance2(const Eigen::Vector3d& x, const CutPatch& p)
{
    const double height = p.normal.dot(x - p.corners[0]);
    if (over(x, p)) return height * height;
    double best = std::numeric_limits<double>::infinity();
    for (std::size_t k = 0; k < p.corners.size(); ++k) best = std::min(best, segment_distance2(x, p.corners[k], p.corners[(k + 1) % p.corners.size()]));
    return best;
}

/// Möller and Trumbore: whether the segment a-b meets the triangle v0 v1 v2 (edges and ends
/// included, so a segment through the seam of two triangles meets one of them).
bool segment_meets_triangle(const Eigen::Vector3d& a, const Eigen::Vector3d& b, const Eigen::Vector3d& v0, const Eigen::Vector3d& v1,
                            const Eigen::Vector3d& v2)
{
    const Eigen::Vector3d d = b - a, e1 = v1 - v0, e2 = v2 - v0;
    const Eigen::Vector3d p = d.cross(e2);
    const double det = e1.dot(p);
    if (std::abs(det) <= 1e-14 * d.norm() * e1.norm() * e2.norm()) return false; // along the triangle's plane
    const double inv = 1.0 / det;
    const Eigen::Vector3d s = a - v0;
    const double u = s.dot(p) * inv;
    if (u < 0.0 || u > 1.0) return false;
    const Eigen::Vector3d q = s.cross(e1);
    const double v = d.dot(q) * inv;
    if (v < 0.0 || u + v > 1.0) return false;
    const double t = e2.dot(q) * inv;
    return t >= 0.0 && t <= 1.0;
}

} // namespace

CutSurface::CutSurface(const PlaneCut& plane) : m_is_plane(true), m_plane(plane) {}

void CutSurface::add(CutPatch patch)
{
    if (patch.corners.size() < 3) return;
    Eigen::Vector3d area = Eigen::Vector3d::Zero();
    for (std::size_t k = 1; k + 1 < patch.corners.size(); ++k)
        area += (patch.corners[k] - patch.corners[0]).cross(patch.corners[k + 1] - patch.corners[0]);
    if (area.dot(patch.normal) < 0.0) std::reverse(patch.corners.begin(), patch.corners.end());
    if (m_patches.empty()) {
        patch.u = patch.normal.unitOrthogonal();
        patch.at.setZero();
    } else { // carried over from the patch before: its axis turned with the normal, its place unrolled
        const CutPatch& before = m_patches.back();
        patch.u = (Eigen::Quaterniond::FromTwoVectors(before.normal, patch.normal) * before.u).normalized();
        const Eigen::Vector3d u = (before.u + patch.u).normalized(), w = (before.normal + patch.normal).normalized().cross(u);
        const Eigen::Vector3d step = patch.corners[0] - before.corners[0];
        patch.at = before.at + Eigen::Vector2d(u.dot(step), w.dot(step));
    }
    Eigen::AlignedBox3d box;
    box.setEmpty();
    for (const Eigen::Vector3d& c : patch.corners) box.extend(c);
    m_boxes.push_back(box);
    m_patches.push_back(std::move(patch));
}

std::size_t CutSurface::nearest(const Eigen::Vector3d& x) const
{
    // The patch whose box is nearest first, then only those whose box could hold a nearer point.
    std::size_t best = 0;
    double best_box = INFINITY;
    for (std::size_t k = 0; k < m_patches.size(); ++k)
        if (const double d = m_boxes[k].squaredExteriorDistance(x); d < best_box) {
            best_box = d;
            best = k;
        }
    double best_distance = patch_distance2(x, m_patches[best]);
    for (std::size_t k = 0; k < m_patches.size(); ++k) {
        if (k == best || m_boxes[k].squaredExteriorDistance(x) >= best_distance) continue;
        const double d = patch_distance2(x, m_patches[k]);
        if (d < best_distance) {
            best_distance = d;
            best = k;
        }
    }
    return best;
}

double CutSurface::level(const Eigen::Vector3d& x) const
{
    if (m_is_plane) return m_plane.at(x);
    if (m_patches.empty()) return 0.0;
    const CutPatch& p = m_patches[nearest(x)];
    return p.normal.dot(x - p.corners[0]);
}

Eigen::Vector3d CutSurface::normal(const Eigen::Vector3d& x) const
{
    if (m_is_plane) return m_plane.normal.normalized();
    return m_patches.empty() ? Eigen::Vector3d::UnitX() : m_patches[nearest(x)].normal;
}

Eigen::Vector2d CutSurface::unrolled(const Eigen::Vector3d& x) const
{
    if (m_is_plane) {
        const Eigen::Vector3d n = m_plane.normal.normalized(), u = n.unitOrthogonal();
        return {u.dot(x), n.cross(u).dot(x)};
    }
    if (m_patches.empty()) return Eigen::Vector2d::Zero();
    const CutPatch& p = m_patches[nearest(x)];
    const Eigen::Vector3d d = x - p.corners[0];
    return p.at + Eigen::Vector2d(p.u.dot(d), p.normal.cross(p.u).dot(d));
}

bool CutSurface::meets(const Eigen::Vector3d& a, const Eigen::Vector3d& b) const
{
    if (m_is_plane) return (m_plane.at(a) < 0.0) != (m_plane.at(b) < 0.0);
    Eigen::AlignedBox3d segment(a.cwiseMin(b), a.cwiseMax(b));
    for (std::size_t k = 0; k < m_patches.size(); ++k) {
        if (!m_boxes[k].intersects(segment)) continue;
        const std::vector<Eigen::Vector3d>& c = m_patches[k].corners;
        for (std::size_t i = 1; i + 1 < c.size(); ++i)
            if (segment_meets_triangle(a, b, c[0], c[i], c[i + 1])) return true;
    }
    return false;
}

bool CutSurface::covers(const Eigen::Vector3d& x, double off) const
{
    if (m_is_plane) return true;
    for (std::size_t k = 0; k < m_patches.size(); ++k)
        if (m_boxes[k].squaredExteriorDistance(x) <= off * off && std::abs(m_patches[k].normal.dot(x - m_patches[k].corners[0])) <= off &&
            over(x, m_patches[k]))
            return true;
    return false;
}

Eigen::AlignedBox3d CutSurface::bounds(std::size_t first) const
{
    if (m_is_plane) {
        const double huge = std::numeric_limits<double>::max();
        return {Eigen::Vector3d::Constant(-huge), Eigen::Vector3d::Constant(huge)};
    }
    Eigen::AlignedBox3d box;
    box.setEmpty();
    for (std::size_t k = first; k < m_boxes.size(); ++k) box.extend(m_boxes[k]);
    return box;
}

} // namespace vox::isxfem
