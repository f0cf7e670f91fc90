#include "sim/haptic_snapshot.hpp"

#include "contact/contact_patch.hpp"

namespace vox::sim {

void take_snapshot(Method& method, std::size_t tool, const io::ToolSpec& spec, const contact::PlacedShape& pose, const Eigen::AlignedBox3d& box,
                   double t_s, contact::SurfacePoints& out)
{
    method.sample_surface(box, spec, out);
    contact::measure_slack(pose, spec.push_margin_mm, out);
    if (spec.haptic_subdivision >= 0)
        if (const std::optional<double> compliance = method.contact_compliance_mm_per_n(tool)) {
            contact::PatchSettings settings;
            settings.levels = spec.haptic_subdivision;
            contact::build_patch(out, pose, {spec.push_margin_mm, spec.contact_stiffness_n_per_mm}, *compliance, settings);
        }
    out.t_s = t_s;
}

} // namespace vox::sim
