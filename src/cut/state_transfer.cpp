#include "cut/state_transfer.hpp"

#include <unordered_map>

namespace vox::cut {

void transfer_state(const grid::UpdateReport& report, const fem::HexModel& old_model, const fem::ImplicitSolver& old_solver,
                    const fem::HexModel& new_model, fem::ImplicitSolver& new_solver)
{
    const int level = new_model.level();
    // Old model element by grid element (level 0: by voxel slot, which cuts never renumber).
    std::unordered_map<std::uint32_t, std::uint32_t> old_element;
    for (std::uint32_t e = 0; e < old_model.elements().size(); ++e) old_element.emplace(old_model.elements()[e].grid_element, e);
    // Where each new grid element came from: itself unless the update created it.
    std::unordered_map<std::uint32_t, std::uint32_t> source;
    if (level > 0 && static_cast<std::size_t>(level) < report.levels.size())
        for (const auto& [created, from] : report.levels[static_cast<std::size_t>(level)].created)
            source[created] = from.empty() ? grid::no_index : from.front();

    std::vector<Eigen::Vector3d>& x = new_solver.positions();
    std::vector<Eigen::Vector3d>& v = new_solver.velocities();
    std::vector<unsigned char> done(new_model.node_count(), 0);
    for (std::uint32_t e = 0; e < new_model.elements().size(); ++e) {
        const fem::HexElement& el = new_model.elements()[e];
        std::uint32_t from = el.grid_element;
        if (const auto s = source.find(from); s != source.end()) from = s->second;
        const auto old = old_element.find(from);
        if (old == old_element.end()) continue; // nothing to inherit: the node stays at rest
        const fem::HexElement& old_el = old_model.elements()[old->second];
        for (int c = 0; c < 8; ++c) {
            const std::uint32_t n = el.dof_node[c];
            if (done[n]) continue;
            done[n] = 1;
            x[n] = old_solver.positions()[old_el.dof_node[c]];
            v[n] = old_solver.velocities()[old_el.dof_node[c]];
        }
        if (const double w = old_solver.water(old->second); w > 0.0) new_solver.set_water(e, w);
        if (old_solver.has_plasticity()) new_solver.set_plastic_strain(e, old_solver.plastic_strain(old->second));
    }
}

} // namespace vox::cut
