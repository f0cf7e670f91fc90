#include "sim/blade_stroke.hpp"

#include "contact/convex_hull.hpp"
#include "contact/tool_shape.hpp"

#include <Eigen/Geometry>

#include <cmath>

namespace vox::sim {
namespace {

double cos_degrees(double degrees) { return std::cos(degrees * 3.14159265358979323846 / 180.0); }

// A frame turns a blade by a few degrees: more is a new stroke (a blade lifted and set down
// elsewhere, or a script's jump), as is drifting across its own plane by more than a hand wavers.
const double k_max_frame_turn_cos = cos_degrees(10.0);
constexpr double k_max_drift_mm = 1.0;

} // namespace

BladeStroke::BladeStroke(const io::ToolSpec& tool)
    : m_profile((tool.shape == io::ToolShape::scalpel ? contact::ToolShape::scalpel(tool.size_mm) : contact::ToolShape::box(tool.size_mm)).profile())
{
}

isxfem::CutReport BladeStroke::advance(IsxfemSimulation& sim, const io::ToolPose& from, const io::ToolPose& to,
                                       const Eigen::Vector3d& moved_mm, Sweep sweep)
{
    const Eigen::Vector3d normal = to.orientation.toRotationMatrix().col(1);
    const Eigen::Vector3d step = to.position_mm - m_last_position_mm; // the blade's, in the world
    // Across the plane halfway through the turn: a blade turning as it goes moves along that.
    const double across = step.dot((m_last_normal + normal).normalized());
    const bool going = !m_surface.patches().empty();
    const bool goes_on = going && normal.dot(m_last_normal) >= k_max_frame_turn_cos && std::abs(m_drift_mm + across) <= k_max_drift_mm;
    m_drift_mm = goes_on ? m_drift_mm + across : 0.0;
    if (!goes_on) {
        m_surface = {};
        m_offered = 0;
        m_cut = -1;
    }
    m_last_normal = normal;
    m_last_position_mm = to.position_mm;
    // The frame's patch: the profile where the frame began (where the blade was, if in the same
    // plane and not where an ended stroke left off) and where it ended, in the plane halfway between.
    const bool from_here = (goes_on || !going) && from.placed && from.orientation.toRotationMatrix().col(1).dot(normal) >= k_max_frame_turn_cos;
    const io::ToolPose& start = from_here ? from : to;
    const Eigen::Matrix3d frame = start.orientation.slerp(0.5, to.orientation).toRotationMatrix(); // the plane halfway
    // Where the blade began and ended the frame in rest space. Going on, it moved there within its
    // plane only: as in the world less the material's own move, each without what crosses the
    // plane (a wavering blade cuts on along its plane, and the material carries the crack along
    // across it), so the crack goes on from where it was rather than stepping sideways.
    Eigen::Vector3d rest_start = start.position_mm - moved_mm, rest_end = to.position_mm - moved_mm;
    if (goes_on && from_here) {
        const Eigen::Vector3d within = (to.position_mm - start.position_mm) - (moved_mm - m_last_moved_mm);
        rest_start = m_last_rest_mm;
        rest_end = rest_start + within - within.dot(frame.col(1)) * frame.col(1);
    }
    m_last_rest_mm = rest_end;
    m_last_moved_mm = moved_mm;
    const Eigen::Vector3d centre_mm = 0.5 * (rest_start + rest_end);
    std::vector<Eigen::Vector2d> placed;
    for (const auto& [pose, at] : {std::pair{&start, rest_start}, std::pair{&to, rest_end}})
        for (const Eigen::Vector2d& p : m_profile) {
            const Eigen::Vector3d local = frame.transpose() * (at + pose->orientation * Eigen::Vector3d(p.x(), 0.0, p.y()) - centre_mm);
            placed.emplace_back(local.x(), local.z());
        }
    isxfem::CutPatch patch;
    patch.normal = frame.col(1);
    for (const Eigen::Vector2d& q : contact::convex_hull(std::move(placed)))
        patch.corners.push_back(1e-3 * (centre_mm + frame.col(0) * q.x() + frame.col(2) * q.y()));
    m_surface.add(std::move(patch));
    if (sweep == Sweep::pass) m_offered = m_surface.patches().size(); // never to be cut
    if (sweep != Sweep::cut) return {};
    const isxfem::CutReport report = sim.cut(m_surface, m_offered, m_cut);
    m_offered = m_surface.patches().size();
    if (report.cut >= 0) m_cut = report.cut;
    return report;
}

} // namespace vox::sim
