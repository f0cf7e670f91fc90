#include "app/blade_stroke.hpp"

#include "contact/tool_shape.hpp"

#include <cmath>

namespace vox::app {
namespace {

// A hand holding a blade wavers: within this tilt and this offset of the plane where the stroke
// began, the blade goes on cutting along that plane (its sweep projected onto it); beyond, a new
// stroke, a new planar cut, begins. Without it a blade driven by a device started a new cut every
// frame and a sweep never added up (a 2 mm blade drawn through a bar, tilting by 0.5 degrees each
// frame: 18 tetrahedra cut in 2 cuts instead of the 54 of its path).
const double k_max_tilt_cos = std::cos(5.0 * 3.14159265358979323846 / 180.0);
constexpr double k_max_offset_mm = 1.0;

} // namespace

BladeStroke::BladeStroke(const io::ToolSpec& tool)
    : m_swept((tool.shape == io::ToolShape::scalpel ? contact::ToolShape::scalpel(tool.size_mm) : contact::ToolShape::box(tool.size_mm))
                  .profile())
{
}

isxfem::CutReport BladeStroke::advance(IsxfemSimulation& sim, const io::ToolPose& from, const io::ToolPose& to,
                                       const Eigen::Vector3d& moved_mm, bool cut)
{
    const Eigen::Matrix3d r = to.orientation.toRotationMatrix();
    const Eigen::Vector3d normal = r.col(1);
    // The stroke goes on while the plane stays put in the world, whether or not it has cut
    // anything yet: a blade shorter than a tetrahedron cuts it once its sweep has covered it.
    const bool same_plane = !m_swept.empty() && normal.dot(m_rotation.col(1)) >= k_max_tilt_cos &&
                            std::abs((to.position_mm - m_world_origin_mm).dot(m_rotation.col(1))) <= k_max_offset_mm;
    if (!same_plane) { // the cut's plane, carried back to rest space where the stroke begins
        m_cut = -1;
        m_rotation = r;
        m_world_origin_mm = to.position_mm;
        m_origin_mm = to.position_mm - moved_mm;
        m_swept.clear();
    }
    // A pose in the stroke's rest-space x-z coordinates: the turn within the plane and the offset
    // (motion across the plane is ignored).
    auto in_plane = [&](const Eigen::Vector3d& p_mm) {
        const Eigen::Vector3d local = m_rotation.transpose() * (p_mm - moved_mm - m_origin_mm);
        return Eigen::Vector2d(local.x(), local.z());
    };
    auto turn = [&](const Eigen::Quaterniond& q) { // the turn about the plane's normal (a tilt off it dropped)
        const Eigen::Matrix3d relative = m_rotation.transpose() * q.toRotationMatrix();
        const double angle = std::atan2(relative(0, 2) - relative(2, 0), relative(0, 0) + relative(2, 2));
        Eigen::Matrix2d m;
        m << std::cos(angle), std::sin(angle), -std::sin(angle), std::cos(angle);
        return m;
    };
    const io::ToolPose& start =
        from.placed && from.orientation.toRotationMatrix().col(1).dot(m_rotation.col(1)) >= k_max_tilt_cos ? from : to;
    m_swept.add(turn(start.orientation), in_plane(start.position_mm), turn(to.orientation), in_plane(to.position_mm));
    if (!cut) return {};
    const auto inside = [this, &moved_mm, &in_plane](const Eigen::Vector3d& p_m) { return m_swept.covers(in_plane(p_m * 1e3 + moved_mm)); };
    const isxfem::CutReport report = sim.cut(m_origin_mm * 1e-3, m_rotation.col(1), inside, m_cut);
    if (report.cut >= 0) m_cut = report.cut;
    return report;
}

} // namespace vox::app
