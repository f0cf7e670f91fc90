#include "sim/run_record.hpp"

#include "core/sample_stats.hpp"

#include <algorithm>
#include <cstdio>

namespace vox::sim {

std::string frame_file_name(int frame, const char* extension)
{
    char name[48];
    std::snprintf(name, sizeof name, "frame_%05d.%s", frame, extension);
    return name;
}

nlohmann::json tool_frames_json(const std::vector<ToolFrame>& tools)
{
    nlohmann::json out = nlohmann::json::array();
    for (const ToolFrame& t : tools) {
        if (!t.placed) {
            out.push_back(nullptr);
            continue;
        }
        out.push_back({{"position_mm", {t.position_mm.x(), t.position_mm.y(), t.position_mm.z()}},
                       {"driver_mm", {t.driver_mm.x(), t.driver_mm.y(), t.driver_mm.z()}},
                       {"coupling_force_n", {t.coupling_force_n.x(), t.coupling_force_n.y(), t.coupling_force_n.z()}},
                       {"force_n", {t.force_n.x(), t.force_n.y(), t.force_n.z()}},
                       {"torque_n_mm", {t.torque_n_mm.x(), t.torque_n_mm.y(), t.torque_n_mm.z()}},
                       {"pressure_pa", t.pressure_pa},
                       {"contact_area_mm2", t.contact_area_mm2},
                       {"cut", t.cut}});
    }
    return out;
}

/// {"LEVEL": elements, ...}: one entry, two for a model of two levels.
static nlohmann::json per_level(const Method& method)
{
    nlohmann::json out = nlohmann::json::object();
    for (const auto& [level, count] : method.elements_per_level()) out[std::to_string(level)] = count;
    return out;
}

RunRecord::RunRecord(const std::string& scene_path, const Method& method, double dt_s)
{
    m_document = {{"scene", scene_path},
                  {"method", method.name()},
                  {"level", method.level()},
                  {"elements", method.element_count()},
                  {"elements_per_level", per_level(method)},
                  {"dofs", method.dof_count()},
                  {"dt_s", dt_s},
                  {"linear_solver", method.linear_solver()},
                  {"level_changes", nlohmann::json::array()},
                  {"frames", nlohmann::json::array()}};
}

void RunRecord::add(const FrameStats& f, const Method& method)
{
    const StepFigures& s = f.step;
    const ToolsFrame& t = f.tools;
    ++m_frames;
    m_total_ms += s.step_ms;
    m_max_ms = std::max(m_max_ms, s.step_ms);
    m_converged += s.converged;
    m_recovered += s.recovered;
    m_projected += s.energy_projected;
    m_fallbacks += !s.preconditioner_fallback.empty();
    m_inverted_frames += s.inverted_elements > 0;
    m_max_stretch = std::max(m_max_stretch, s.max_stretch);
    m_removed += t.cut.removed_voxels;
    m_separated_faces += t.cut.separated_faces;
    m_separated_voxels += t.cut.separated_voxels;
    if (t.cut.changed()) m_cutting_ms.push_back(t.cutting_ms());
    m_frame_ms.push_back(f.frame_ms);
    m_last = s;
    nlohmann::json frame{{"frame", f.frame},
                         {"t_s", f.t_s},
                         {"level", f.level},
                         {"frame_ms", f.frame_ms},
                         {"step_ms", s.step_ms},
                         {"assembly_ms", s.assembly_ms},
                         {"solve_ms", s.solve_ms},
                         {"cg_iterations", s.cg_iterations},
                         {"newton_iterations", s.newton_iterations},
                         {"residual", s.residual},
                         {"converged", s.converged},
                         {"recovered", s.recovered},
                         {"substeps", s.substeps},
                         {"energy_projected", s.energy_projected},
                         {"asleep_pieces", s.asleep_pieces},
                         {"kinetic_energy_j", s.kinetic_energy_j},
                         {"elastic_energy_j", s.elastic_energy_j ? nlohmann::json(*s.elastic_energy_j) : nlohmann::json()},
                         {"max_displacement_mm", s.max_displacement_mm},
                         {"inverted_elements", s.inverted_elements},
                         {"max_stretch", s.max_stretch},
                         {"collision_ms", t.collision_ms},
                         {"propagation_ms", t.propagation_ms},
                         {"grid_update_ms", t.cut.grid_update_ms},
                         {"remesh_ms", t.cut.remesh_ms},
                         {"fem_update_ms", t.cut.fem_update_ms},
                         {"removed_voxels", t.cut.removed_voxels},
                         {"separated_faces", t.cut.separated_faces},
                         {"separated_voxels", t.cut.separated_voxels},
                         {"elements", method.element_count()},
                         {"dofs", method.dof_count()},
                         {"object_held", t.hold_object},
                         {"tools", tool_frames_json(t.tools)}};
    if (f.level_change) {
        const LevelChange& c = *f.level_change;
        const nlohmann::json change{{"frame", f.frame}, {"t_s", f.t_s}, {"from", c.from}, {"to", c.to}, {"reason", c.reason}, {"ms", c.ms}};
        frame["level_change"] = change;
        m_document["level_changes"].push_back(change);
    }
    if (!method.obstacles().empty()) {
        const Eigen::Vector3d force = method.obstacle_force_n();
        frame["obstacle_force_n"] = {force.x(), force.y(), force.z()};
    }
    if (const PieceContactFigures c = method.piece_contact(); c.enabled) {
        frame["piece_contact"] = {{"contacts", c.contacts}, {"edge_contacts", c.edge_contacts}, {"tested_vertices", c.tested_vertices}, {"force_n", c.force_n}, {"ms", c.ms},
                                  {"max_depth_mm", c.max_depth_mm}};
    }
    for (const PatchFrame& p : f.patches) {
        if (p.asked) {
            auto& [touched, patched] = m_patch_use[p.tool];
            touched += p.touching;
            patched += p.points > 0;
        }
        if (p.points == 0) continue;
        ++m_patch_frames;
        frame["haptic_patch"].push_back({{"tool", p.tool}, {"points", p.points}, {"level", p.level}, {"compliance_mm_per_n", p.compliance_mm_per_n},
                                         {"displacement_mm", p.displacement_mm}, {"step_us_max", p.step_us_max}});
    }
    if (!s.preconditioner_fallback.empty()) frame["preconditioner_fallback"] = s.preconditioner_fallback;
    method.add_frame_figures(frame);
    m_document["frames"].push_back(std::move(frame));
}

std::vector<std::pair<std::string, std::size_t>> RunRecord::tools_given_no_patch() const
{
    std::vector<std::pair<std::string, std::size_t>> out;
    for (const auto& [tool, use] : m_patch_use)
        if (use.first > 0 && use.second == 0) out.emplace_back(tool, use.first);
    return out;
}

void RunRecord::finish(const Method& method)
{
    nlohmann::json summary{{"frames", m_frames},
                           {"total_step_ms", m_total_ms},
                           {"mean_step_ms", m_frames ? m_total_ms / m_frames : 0.0},
                           {"max_step_ms", m_max_ms},
                           {"frame_ms_median", quantile(m_frame_ms, 0.5)},
                           {"frame_ms_p95", quantile(m_frame_ms, 0.95)},
                           {"frame_ms_max", quantile(m_frame_ms, 1.0)},
                           {"level_changes", m_document["level_changes"].size()},
                           {"final_level", method.level()},
                           {"converged_frames", m_converged},
                           {"nonconverged_steps", m_frames - m_converged},
                           {"recovered_steps", m_recovered},
                           {"preconditioner_fallbacks", m_fallbacks},
                           {"energy_projected_frames", m_projected},
                           {"inverted_frames", m_inverted_frames},
                           {"max_stretch", m_max_stretch},
                           {"removed_voxels", m_removed},
                           {"separated_faces", m_separated_faces},
                           {"separated_voxels", m_separated_voxels},
                           {"cutting_frames", m_cutting_ms.size()},
                           {"haptic_patch_frames", m_patch_frames},
                           {"cutting_ms_p95", quantile(m_cutting_ms, 0.95)},
                           {"final_elements", method.element_count()},
                           {"final_dofs", method.dof_count()},
                           {"pieces", method.piece_count()},
                           {"final_max_displacement_mm", m_last.max_displacement_mm},
                           {"final_elastic_energy_j", m_last.elastic_energy_j ? nlohmann::json(*m_last.elastic_energy_j) : nlohmann::json()},
                           {"final_kinetic_energy_j", m_last.kinetic_energy_j}};
    method.add_summary_figures(summary);
    m_document["summary"] = std::move(summary);
    m_document["linear_solver"] = method.linear_solver(); // after a fallback: what took over and why
}

} // namespace vox::sim
