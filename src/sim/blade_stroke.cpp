#include "sim/blade_stroke.hpp"

#include "contact/convex_hull.hpp"
#include "contact/tool_shape.hpp"

#include <Eigen/Geometry>

#include <algorithm>
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
    const bool going = !m_surface.patches().empty();
    // The crack is what the edge sweeps: the plane holding the edge and the way the blade moves
    // (its own plane when it moves along it). A blade held at a slant to the way it moves, as a
    // hand holds it, otherwise drifted across its own plane and started a new crack beside the
    // last about every millimetre (a staircase of cracks: 2 to 4 cracks through a sagging rod).
    // Moving along its plane, the plane halfway through the frame's turn (a turning blade moves
    // along that).
    const Eigen::Vector3d swept = to.orientation.toRotationMatrix().col(0).cross(step);
    Eigen::Vector3d cut_normal = !going                                        ? normal
                                 : swept.norm() > 0.2 * step.norm() && step.norm() > 1e-9 ? Eigen::Vector3d(swept.normalized() * (swept.dot(normal) < 0.0 ? -1.0 : 1.0))
                                                                               : Eigen::Vector3d((m_last_normal + normal).normalized());
    const double across = step.dot(cut_normal);
    const bool goes_on = going && normal.dot(m_last_normal) >= k_max_frame_turn_cos && std::abs(m_drift_mm + across) <= k_max_drift_mm;
    m_drift_mm = goes_on ? m_drift_mm + across : 0.0;
    if (!goes_on) {
        m_surface = {};
        m_offered = 0;
        m_cut = -1;
        cut_normal = normal;
    }
    m_last_normal = normal;
    m_last_position_mm = to.position_mm;
    // The frame's patch: the profile where the frame began (where the blade was, if in the same
    // plane and not where an ended stroke left off) and where it ended, laid into the cut plane.
    const bool from_here = (goes_on || !going) && from.placed && from.orientation.toRotationMatrix().col(1).dot(normal) >= k_max_frame_turn_cos;
    const io::ToolPose& start = from_here ? from : to;
    // Where the blade began and ended the frame in rest space. Going on, it moved there within the
    // cut plane only: as in the world less the material's own move, each without what crosses the
    // plane (a wavering blade cuts on along its plane, and the material carries the crack along
    // across it), so the crack goes on from where it was rather than stepping sideways.
    Eigen::Vector3d rest_start = start.position_mm - moved_mm, rest_end = to.position_mm - moved_mm;
    if (goes_on && from_here) {
        const Eigen::Vector3d within = (to.position_mm - start.position_mm) - (moved_mm - m_last_moved_mm);
        rest_start = m_last_rest_mm;
        rest_end = rest_start + within - within.dot(cut_normal) * cut_normal;
    }
    m_last_rest_mm = rest_end;
    m_last_moved_mm = moved_mm;
    // The cut plane goes through the middle of the blade's edge where the frame began; its axes
    // are the edge (as it lies in the plane) and the plane's normal crossed with it.
    double edge_z = m_profile.front().y();
    for (const Eigen::Vector2d& p : m_profile) edge_z = std::min(edge_z, p.y());
    const Eigen::Vector3d through = rest_start + start.orientation * Eigen::Vector3d(0.0, 0.0, edge_z);
    Eigen::Vector3d along = start.orientation.slerp(0.5, to.orientation).toRotationMatrix().col(0);
    along = (along - along.dot(cut_normal) * cut_normal).normalized();
    const Eigen::Vector3d up = cut_normal.cross(along);
    std::vector<Eigen::Vector2d> placed;
    for (const auto& [pose, at] : {std::pair{&start, rest_start}, std::pair{&to, rest_end}})
        for (const Eigen::Vector2d& p : m_profile) {
            const Eigen::Vector3d q = at + pose->orientation * Eigen::Vector3d(p.x(), 0.0, p.y()) - through;
            placed.emplace_back(q.dot(along), q.dot(up));
        }
    isxfem::CutPatch patch;
    patch.normal = cut_normal;
    for (const Eigen::Vector2d& q : contact::convex_hull(std::move(placed))) patch.corners.push_back(1e-3 * (through + along * q.x() + up * q.y()));
    m_surface.add(std::move(patch));
    if (sweep == Sweep::pass) m_offered = m_surface.patches().size(); // never to be cut
    if (sweep != Sweep::cut) return {};
    const isxfem::CutReport report = sim.cut(m_surface, m_offered, m_cut);
    m_offered = m_surface.patches().size();
    if (report.cut >= 0) m_cut = report.cut;
    return report;
}

} // namespace vox::sim
