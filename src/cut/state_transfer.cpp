#include "cut/state_transfer.hpp"

#include <array>
#include <limits>
#include <stdexcept>
#include <unordered_map>

namespace vox::cut {
namespace {

std::uint64_t key(int level, std::uint32_t grid_element) { return (std::uint64_t{static_cast<std::uint32_t>(level)} << 32) | grid_element; }
std::uint64_t key(const fem::HexElement& el) { return key(el.level, el.grid_element); }

int node_level(const fem::HexModel& model, std::uint32_t n) { return model.node_levels().empty() ? model.level() : model.node_levels()[n]; }

/// A model of two levels: its tied nodes placed and moving on the field of the coarse nodes they
/// follow (the transfer gave them the old field, which a fine region may have bent past it).
void follow_ties(const fem::HexModel& model, fem::ImplicitSolver& solver)
{
    std::vector<Eigen::Vector3d>& x = solver.positions();
    std::vector<Eigen::Vector3d>& v = solver.velocities();
    const auto& rest = model.rest_positions();
    for (const grid::MixedLevels::Tie& t : model.ties()) {
        Eigen::Vector3d u = Eigen::Vector3d::Zero(), w = Eigen::Vector3d::Zero();
        for (std::size_t c = 0; c < 8; ++c) {
            u += t.weights[c] * (x[t.masters[c]] - rest[t.masters[c]]);
            w += t.weights[c] * v[t.masters[c]];
        }
        x[t.node] = rest[t.node] + u;
        v[t.node] = w;
    }
}

/// A model's elements and nodes by level and grid id, for the one or two levels it has (fine
/// first); no_index where it has none there.
class ModelIndex {
public:
    ModelIndex(const grid::BranchedGrid& grid, const fem::HexModel& model) : m_grid(grid)
    {
        for (const int level : {model.level(), model.coarse_level()})
            if (m_levels.empty() || m_levels.back().level != level)
                m_levels.push_back({level, std::vector<std::uint32_t>(grid.level(level).elements.size(), grid::no_index),
                                    std::vector<std::uint32_t>(grid.level(level).node_users.size(), grid::no_index)});
        for (std::uint32_t e = 0; e < model.elements().size(); ++e)
            at(model.elements()[e].level).elements[model.elements()[e].grid_element] = e;
        for (std::uint32_t n = 0; n < model.grid_node().size(); ++n) at(node_level(model, n)).nodes[model.grid_node()[n]] = n;
    }
    [[nodiscard]] std::uint32_t element(int level, std::uint32_t id) const { return find(level, id, &Level::elements); }
    [[nodiscard]] std::uint32_t node(int level, std::uint32_t id) const { return find(level, id, &Level::nodes); }
    /// The element holding fine voxel `voxel` (the fine level's, else the coarse one's).
    [[nodiscard]] std::uint32_t holding(std::uint32_t voxel) const
    {
        for (const Level& l : m_levels)
            if (const std::uint32_t e = l.elements[m_grid.element_of(voxel, l.level)]; e != grid::no_index) return e;
        throw std::logic_error("transfer_between_levels: a voxel in no element of the old model");
    }

private:
    struct Level {
        int level;
        std::vector<std::uint32_t> elements, nodes; ///< by grid element, by grid node
    };
    Level& at(int level) { return m_levels.front().level == level ? m_levels.front() : m_levels.back(); }
    std::uint32_t find(int level, std::uint32_t id, std::vector<std::uint32_t> Level::*ids) const
    {
        for (const Level& l : m_levels)
            if (l.level == level) return id < (l.*ids).size() ? (l.*ids)[id] : grid::no_index;
        return grid::no_index;
    }
    const grid::BranchedGrid& m_grid;
    std::vector<Level> m_levels;
};

} // namespace

void transfer_state(const grid::UpdateReport& report, const fem::HexModel& old_model, const fem::ImplicitSolver& old_solver,
                    const fem::HexModel& new_model, fem::ImplicitSolver& new_solver)
{
    // Old model element by level and grid element (level 0: by voxel slot, which cuts never
    // renumber); a model of two levels has elements of both.
    std::unordered_map<std::uint64_t, std::uint32_t> old_element;
    for (std::uint32_t e = 0; e < old_model.elements().size(); ++e) old_element.emplace(key(old_model.elements()[e]), e);
    // Where each new grid element came from: itself unless the update created it.
    std::unordered_map<std::uint64_t, std::uint32_t> source;
    for (const int level : {new_model.level(), new_model.coarse_level()})
        if (level > 0 && static_cast<std::size_t>(level) < report.levels.size())
            for (const auto& [created, from] : report.levels[static_cast<std::size_t>(level)].created)
                source[key(level, created)] = from.empty() ? grid::no_index : from.front();

    std::vector<Eigen::Vector3d>& x = new_solver.positions();
    std::vector<Eigen::Vector3d>& v = new_solver.velocities();
    std::vector<unsigned char> done(new_model.node_count(), 0);
    for (std::uint32_t e = 0; e < new_model.elements().size(); ++e) {
        const fem::HexElement& el = new_model.elements()[e];
        std::uint32_t from = el.grid_element;
        if (const auto s = source.find(key(el)); s != source.end()) from = s->second;
        const auto old = old_element.find(key(el.level, from));
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
    follow_ties(new_model, new_solver);
}

void transfer_between_levels(const grid::BranchedGrid& grid, const fem::HexModel& old_model, const fem::ImplicitSolver& old_solver,
                             const fem::HexModel& new_model, fem::ImplicitSolver& new_solver)
{
    if (old_model.level() < 1 || new_model.level() < 1) throw std::invalid_argument("transfer_between_levels: levels start at 1");
    const ModelIndex old_index(grid, old_model);
    const auto& old_x = old_solver.positions();
    const auto& old_v = old_solver.velocities();
    const auto& old_rest = old_model.rest_positions();
    // The old model's displacement and velocity at index-space point p, in its element me.
    const auto field_at = [&](const fem::HexElement& me, const Eigen::Vector3d& p, Eigen::Vector3d& u, Eigen::Vector3d& v) {
        const grid::Element& el = grid.level(me.level).elements[me.grid_element];
        const Eigen::Vector3d t = (p - grid::BranchedGrid::cell_corner_index(el.cell, me.level, 0)) / static_cast<double>(1 << me.level);
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
    // What both models have keeps its state as it is: a node on the same grid node of the same
    // level, an element on the same grid element (a move of the fine region changes a few cells;
    // searching every coarse element's thousands of voxels took most of a move on the liver).
    for (std::uint32_t n = 0; n < new_model.grid_node().size(); ++n)
        if (const std::uint32_t o = old_index.node(node_level(new_model, n), new_model.grid_node()[n]); o != grid::no_index) {
            x[n] = old_solver.positions()[o];
            v[n] = old_solver.velocities()[o];
            done[n] = 1;
        }
    const bool wet = [&] {
        for (std::uint32_t e = 0; e < old_model.elements().size(); ++e)
            if (old_solver.water(e) > 0.0) return true;
        return false;
    }();
    for (std::uint32_t e = 0; e < new_model.elements().size(); ++e) {
        const fem::HexElement& me = new_model.elements()[e];
        const std::uint32_t same = old_index.element(me.level, me.grid_element);
        if (same != grid::no_index) {
            if (const double w = old_solver.water(same); w > 0.0) new_solver.set_water(e, w);
            if (old_solver.has_plasticity()) new_solver.set_plastic_strain(e, old_solver.plastic_strain(same));
            if (std::all_of(me.dof_node.begin(), me.dof_node.end(), [&](std::uint32_t n) { return done[n] != 0; })) continue;
        }
        const grid::Element& ge = grid.level(me.level).elements[me.grid_element];
        // Per corner, the element's voxel nearest it (its material is what the node follows).
        std::array<Eigen::Vector3d, 8> corner;
        std::array<double, 8> best;
        std::array<std::uint32_t, 8> nearest{};
        for (int c = 0; c < 8; ++c) corner[c] = grid::BranchedGrid::cell_corner_index(ge.cell, me.level, c);
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
            if (same == grid::no_index && (wet || old_solver.has_plasticity())) {
                const std::uint32_t source = old_index.holding(voxel);
                water += old_solver.water(source);
                if (old_solver.has_plasticity()) plastic += old_solver.plastic_strain(source);
            }
        }
        if (ge.voxels.empty()) continue;
        const double voxels = static_cast<double>(ge.voxels.size());
        if (same == grid::no_index && water > 0.0) new_solver.set_water(e, water / voxels);
        if (same == grid::no_index && old_solver.has_plasticity()) new_solver.set_plastic_strain(e, plastic / voxels);
        for (int c = 0; c < 8; ++c) {
            const std::uint32_t n = me.dof_node[static_cast<std::size_t>(c)];
            if (done[n]) continue;
            done[n] = 1;
            Eigen::Vector3d u, velocity;
            field_at(old_model.elements()[old_index.holding(nearest[c])], corner[c], u, velocity);
            x[n] = new_rest[n] + u;
            v[n] = velocity;
        }
    }
    follow_ties(new_model, new_solver);
}

} // namespace vox::cut
