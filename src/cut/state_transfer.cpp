#include "cut/state_transfer.hpp"

#include <array>
#include <limits>
#include <stdexcept>
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

void transfer_between_levels(const grid::BranchedGrid& grid, const fem::HexModel& old_model, const fem::ImplicitSolver& old_solver,
                             const fem::HexModel& new_model, fem::ImplicitSolver& new_solver)
{
    const int from = old_model.level(), to = new_model.level();
    if (from < 1 || to < 1) throw std::invalid_argument("transfer_between_levels: levels start at 1");
    const grid::Level& old_level = grid.level(from);
    const grid::Level& new_level = grid.level(to);
    std::vector<std::uint32_t> old_element(old_level.elements.size(), grid::no_index); // grid element -> model element
    for (std::uint32_t e = 0; e < old_model.elements().size(); ++e) old_element[old_model.elements()[e].grid_element] = e;
    const auto& old_x = old_solver.positions();
    const auto& old_v = old_solver.velocities();
    const auto& old_rest = old_model.rest_positions();
    // The old level's displacement and velocity at index-space point p, in old grid element ge.
    const auto field_at = [&](std::uint32_t ge, const Eigen::Vector3d& p, Eigen::Vector3d& u, Eigen::Vector3d& v) {
        const grid::Element& el = old_level.elements[ge];
        const fem::HexElement& me = old_model.elements()[old_element[ge]];
        const Eigen::Vector3d t = (p - grid::BranchedGrid::cell_corner_index(el.cell, from, 0)) / static_cast<double>(1 << from);
        const Eigen::Vector3d s = Eigen::Vector3d::Ones() - t;
        u.setZero();
        v.setZero();
        for (int c = 0; c < 8; ++c) {
            const double w = ((c & 1) ? t.x() : s.x()) * ((c & 2) ? t.y() : s.y()) * ((c & 4) ? t.z() : s.z());
            const std::uint32_t n = me.dof_node[static_cast<std::size_t>(c)];
            u += w * (old_x[n] - old_rest[n]);
            v += w * old_v[n];
        }
    };
    std::vector<Eigen::Vector3d>& x = new_solver.positions();
    std::vector<Eigen::Vector3d>& v = new_solver.velocities();
    const auto& new_rest = new_model.rest_positions();
    std::vector<unsigned char> done(new_model.node_count(), 0);
    const bool wet = [&] {
        for (std::uint32_t e = 0; e < old_model.elements().size(); ++e)
            if (old_solver.water(e) > 0.0) return true;
        return false;
    }();
    for (std::uint32_t e = 0; e < new_model.elements().size(); ++e) {
        const fem::HexElement& me = new_model.elements()[e];
        const grid::Element& ge = new_level.elements[me.grid_element];
        // Per corner, the element's voxel nearest it (its material is what the node follows).
        std::array<Eigen::Vector3d, 8> corner;
        std::array<double, 8> best;
        std::array<std::uint32_t, 8> nearest{};
        for (int c = 0; c < 8; ++c) corner[c] = grid::BranchedGrid::cell_corner_index(ge.cell, to, c);
        best.fill(std::numeric_limits<double>::infinity());
        double water = 0.0;
        Eigen::Matrix3d plastic = Eigen::Matrix3d::Zero();
        for (std::uint32_t voxel : ge.voxels) {
            const Eigen::Vector3d p = grid.voxels().coord(voxel).cast<double>();
            for (int c = 0; c < 8; ++c)
                if (const double d = (p - corner[c]).squaredNorm(); d < best[c]) {
                    best[c] = d;
                    nearest[c] = voxel;
                }
            if (wet || old_solver.has_plasticity()) {
                const std::uint32_t source = old_element[grid.element_of(voxel, from)];
                water += old_solver.water(source);
                if (old_solver.has_plasticity()) plastic += old_solver.plastic_strain(source);
            }
        }
        if (ge.voxels.empty()) continue;
        const double voxels = static_cast<double>(ge.voxels.size());
        if (water > 0.0) new_solver.set_water(e, water / voxels);
        if (old_solver.has_plasticity()) new_solver.set_plastic_strain(e, plastic / voxels);
        for (int c = 0; c < 8; ++c) {
            const std::uint32_t n = me.dof_node[static_cast<std::size_t>(c)];
            if (done[n]) continue;
            done[n] = 1;
            Eigen::Vector3d u, velocity;
            field_at(grid.element_of(nearest[c], from), corner[c], u, velocity);
            x[n] = new_rest[n] + u;
            v[n] = velocity;
        }
    }
}

} // namespace vox::cut
