#include "fem/hex_model.hpp"

#include "core/error.hpp"
#include "fem/element_kernel.hpp"
#include "grid/hex8.hpp"
#include "core/union_find.hpp"

#include <Eigen/LU>

#include <algorithm>
#include <numeric>

namespace vox::fem {
namespace {

/// Stiffness of the fictitious material in the empty part of partial elements, and the mass floor
/// of their nodes, as fractions of a full cell's.
constexpr double k_fictitious_fraction = 1e-3;

/// dN_c/dX at local coordinates t in [0, 1]^3 of a box with edges `edge` (m).
Eigen::Matrix<double, 8, 3> corner_gradients(const Eigen::Vector3d& t, const Eigen::Vector3d& edge)
{
    Eigen::Matrix<double, 8, 3> g;
    auto f = [](int bit, double x) { return bit ? x : 1.0 - x; };
    auto df = [](int bit) { return bit ? 1.0 : -1.0; };
    for (int c = 0; c < 8; ++c) {
        const int bx = c & 1, by = (c >> 1) & 1, bz = (c >> 2) & 1;
        g(c, 0) = df(bx) * f(by, t.y()) * f(bz, t.z()) / edge.x();
        g(c, 1) = f(bx, t.x()) * df(by) * f(bz, t.z()) / edge.y();
        g(c, 2) = f(bx, t.x()) * f(by, t.y()) * df(bz) / edge.z();
    }
    return g;
}

} // namespace

HexModel::HexModel(const grid::BranchedGrid& grid, int level) : m_level(level), m_coarse_level(level), m_materials(grid.materials())
{
    if (level < 0 || level > grid.max_level())
        throw InputError("the simulated level must be 0 .. " + std::to_string(grid.max_level()) + ", got " +
                         std::to_string(level));
    const Eigen::Matrix4d& t = grid.voxels().index_to_world();
    m_frame = t.topLeftCorner<3, 3>() * (grid.voxels().voxel_size_m() * 1e3).cwiseInverse().asDiagonal();
    if (level == 0)
        build_voxel_level(grid);
    else
        build_grid_level(grid, level, nullptr, nullptr);
    add_mass_floor(grid);
}

HexModel::HexModel(const grid::BranchedGrid& grid, int level, const HexModel& previous, const std::vector<unsigned char>& changed)
    : m_level(level), m_coarse_level(level), m_materials(grid.materials())
{
    if (level < 1 || level > grid.max_level() || previous.level() != level)
        throw InputError("a model rebuilt from a previous one needs the same level, 1 .. " + std::to_string(grid.max_level()));
    const Eigen::Matrix4d& t = grid.voxels().index_to_world();
    m_frame = t.topLeftCorner<3, 3>() * (grid.voxels().voxel_size_m() * 1e3).cwiseInverse().asDiagonal();
    build_grid_level(grid, level, &previous, &changed);
    add_mass_floor(grid);
}

HexModel::HexModel(const grid::BranchedGrid& grid, const grid::MixedLevels& mixed, const HexModel* previous,
                   const std::array<const std::vector<unsigned char>*, 2>& changed)
    : m_level(mixed.fine()), m_coarse_level(mixed.coarse()), m_materials(grid.materials()), m_ties(mixed.ties())
{
    const Eigen::Matrix4d& t = grid.voxels().index_to_world();
    const Eigen::Vector3d h = grid.voxels().voxel_size_m();
    m_frame = t.topLeftCorner<3, 3>() * (h * 1e3).cwiseInverse().asDiagonal();
    for (const Eigen::Vector3d& p : mixed.rest_positions_mm()) m_rest_world.push_back(p * 1e-3);
    m_nodal_mass.assign(m_rest_world.size(), 0.0);
    for (std::uint32_t n = 0; n < m_rest_world.size(); ++n) {
        m_node_level.push_back(mixed.node_level(n));
        m_grid_node.push_back(mixed.grid_node(n));
    }
    // Each level's full cells share their matrices (reserved first: elements point into them).
    const std::size_t materials = grid.materials().size();
    m_full_stiffness.reserve(2 * materials);
    for (int level : {mixed.fine(), mixed.coarse()})
        for (const grid::ElasticMaterial& m : grid.materials())
            m_full_stiffness.push_back(to_component_major(static_cast<double>(1 << level) * grid::hex8_stiffness(h, m.lame)));
    // Elements of `previous` by level (fine, coarse) and grid element, for those the change left
    // alone: a move of the fine region re-evaluates only the elements new to the model.
    std::array<std::vector<std::uint32_t>, 2> kept;
    if (previous)
        for (std::uint32_t e = 0; e < previous->elements().size(); ++e) {
            const HexElement& old = previous->elements()[e];
            const int k = old.level == mixed.fine() ? 0 : old.level == mixed.coarse() ? 1 : -1;
            if (k < 0) continue;
            const std::vector<unsigned char>* flags = changed[static_cast<std::size_t>(k)];
            if (flags && old.grid_element < flags->size() && (*flags)[old.grid_element]) continue;
            std::vector<std::uint32_t>& ids = kept[static_cast<std::size_t>(k)];
            if (ids.empty()) ids.assign(grid.level(old.level).elements.size(), grid::no_index);
            if (old.grid_element < ids.size()) ids[old.grid_element] = e;
        }
    m_partial_stiffness.reserve(mixed.elements().size());
    m_elements.reserve(mixed.elements().size());
    for (const grid::MixedLevels::Element& el : mixed.elements()) {
        const std::size_t k = el.level == mixed.fine() ? 0 : 1;
        const std::uint32_t old = el.element < kept[k].size() ? kept[k][el.element] : grid::no_index;
        add_grid_element(grid, el.level, el.element, el.nodes, m_full_stiffness.data() + k * materials,
                         old == grid::no_index ? nullptr : &previous->elements()[old],
                         old == grid::no_index ? nullptr : previous->m_partial_stiffness[old]);
    }
    add_mass_floor(grid);
}

void HexModel::build_voxel_level(const grid::BranchedGrid& grid)
{
    // Every voxel is an element; corners are shared through connected faces (the closure of face
    // sharing, as on every other level), numbered by union-find over 8 corner slots per voxel.
    const grid::FineVoxels& v = grid.voxels();
    const Eigen::Vector3d h = v.voxel_size_m();
    UnionFind sets(8 * std::size_t{v.slots()});
    for (std::uint32_t a = 0; a < v.slots(); ++a) {
        if (!v.alive(a)) continue;
        for (int axis = 0; axis < 3; ++axis) {
            const std::uint32_t b = v.connected_neighbour(a, axis);
            if (b == grid::FineVoxels::missing) continue;
            for (int c = 0; c < 8; ++c)
                if ((c >> axis) & 1) sets.unite(8 * a + static_cast<std::uint32_t>(c), 8 * b + static_cast<std::uint32_t>(c ^ (1 << axis)));
        }
    }
    for (const grid::ElasticMaterial& m : grid.materials()) m_full_stiffness.push_back(to_component_major(grid::hex8_stiffness(h, m.lame)));
    std::vector<Matrix8d> mass;
    for (const grid::ElasticMaterial& m : grid.materials()) mass.push_back(grid::hex8_mass(h, m.density_kg_m3));
    const Eigen::Matrix<double, 8, 3> gradient = corner_gradients(Eigen::Vector3d::Constant(0.5), h);

    std::vector<std::uint32_t> dense(8 * std::size_t{v.slots()}, grid::no_index);
    for (std::uint32_t a = 0; a < v.slots(); ++a) {
        if (!v.alive(a)) continue;
        HexElement el;
        el.grid_element = a;
        const auto material = static_cast<std::size_t>(v.material(a));
        el.stiffness = &m_full_stiffness[material];
        el.mass = mass[material];
        el.gradient = gradient;
        el.material = v.material(a);
        el.volume_m3 = h.prod();
        const Eigen::Vector3d centre = v.coord(a).cast<double>();
        el.centroid = v.world_mm(centre) * 1e-3;
        for (int c = 0; c < 8; ++c) {
            const Eigen::Vector3d corner = grid::BranchedGrid::cell_corner_index(v.coord(a), 0, c);
            el.rest.segment<3>(3 * c) = corner.cwiseProduct(h);
            std::uint32_t& id = dense[sets.find(8 * a + static_cast<std::uint32_t>(c))];
            if (id == grid::no_index) {
                id = static_cast<std::uint32_t>(m_rest_world.size());
                m_rest_world.push_back(v.world_mm(corner) * 1e-3);
                m_nodal_mass.push_back(0.0);
            }
            el.dof_node[c] = id;
            m_nodal_mass[id] += el.mass.row(c).sum();
        }
        m_elements.push_back(el);
    }
}

void HexModel::build_grid_level(const grid::BranchedGrid& grid, int level, const HexModel* previous,
                                const std::vector<unsigned char>* changed)
{
    // Elements of `previous` by grid element, for those the change left alone.
    std::vector<std::uint32_t> kept;
    if (previous) {
        kept.assign(grid.level(level).elements.size(), grid::no_index);
        for (std::uint32_t e = 0; e < previous->elements().size(); ++e) {
            const std::uint32_t g = previous->elements()[e].grid_element;
            if (g < kept.size() && !(g < changed->size() && (*changed)[g])) kept[g] = e;
        }
    }
    const grid::Level& lv = grid.level(level);
    const Eigen::Vector3d h = grid.voxels().voxel_size_m(); // voxel edges, m
    const double cell = static_cast<double>(1 << level);

    // Dense numbering of the nodes the alive elements use. After a change, the nodes of the
    // previous model that are still used keep their order and come first, new ones after them: a
    // cut that only adds nodes (opening faces) keeps every old number, so the solver's
    // preconditioner goes on with its factor and patches the rows the cut changed (a factor
    // taken anew took about 130 ms on the liver at level 4).
    m_dense_node.assign(lv.node_users.size(), grid::no_index);
    std::size_t alive = 0;
    if (previous) {
        std::vector<unsigned char> used(lv.node_users.size(), 0);
        for (const grid::Element& g : lv.elements)
            if (g.alive)
                for (std::uint32_t n : g.nodes) used[n] = 1;
        for (std::uint32_t n : previous->m_grid_node)
            if (n < used.size() && used[n] && m_dense_node[n] == grid::no_index) {
                m_dense_node[n] = static_cast<std::uint32_t>(m_grid_node.size());
                m_grid_node.push_back(n);
            }
    }
    for (std::uint32_t e = 0; e < lv.elements.size(); ++e) {
        if (!lv.elements[e].alive) continue;
        ++alive;
        for (std::uint32_t n : lv.elements[e].nodes)
            if (m_dense_node[n] == grid::no_index) {
                m_dense_node[n] = static_cast<std::uint32_t>(m_grid_node.size());
                m_grid_node.push_back(n);
            }
    }
    const auto grid_rest = grid.rest_node_positions(level);
    m_rest_world.resize(m_grid_node.size());
    for (std::size_t i = 0; i < m_grid_node.size(); ++i) m_rest_world[i] = grid_rest[m_grid_node[i]] * 1e-3;
    m_nodal_mass.assign(m_grid_node.size(), 0.0);

    m_full_stiffness.reserve(grid.materials().size());
    for (const grid::ElasticMaterial& m : grid.materials())
        m_full_stiffness.push_back(to_component_major(cell * grid::hex8_stiffness(h, m.lame)));
    m_partial_stiffness.reserve(alive);
    m_elements.reserve(alive);
    for (std::uint32_t e = 0; e < lv.elements.size(); ++e) {
        const grid::Element& g = lv.elements[e];
        if (!g.alive) continue;
        std::array<std::uint32_t, 8> nodes{};
        for (int c = 0; c < 8; ++c) nodes[static_cast<std::size_t>(c)] = m_dense_node[g.nodes[static_cast<std::size_t>(c)]];
        const bool keep = previous && kept[e] != grid::no_index;
        add_grid_element(grid, level, e, nodes, m_full_stiffness.data(), keep ? &previous->elements()[kept[e]] : nullptr,
                         keep ? previous->m_partial_stiffness[kept[e]] : nullptr);
    }
}

void HexModel::add_grid_element(const grid::BranchedGrid& grid, int level, std::uint32_t e, const std::array<std::uint32_t, 8>& nodes,
                                const Matrix24d* full, const HexElement* old, std::shared_ptr<const Matrix24d> old_stiffness)
{
    const grid::Element& g = grid.level(level).elements[e];
    const Eigen::Vector3d h = grid.voxels().voxel_size_m(); // voxel edges, m
    const double cell = static_cast<double>(1 << level);
    HexElement el;
    el.grid_element = e;
    el.level = level;
    el.dof_node = nodes;
    if (grid.is_full(level, e)) {
        el.stiffness = &full[static_cast<std::size_t>(g.content[0].material)];
        m_partial_stiffness.emplace_back();
    } else if (old) {
        m_partial_stiffness.push_back(std::move(old_stiffness)); // fictitious material included
        el.stiffness = m_partial_stiffness.back().get();
    } else {
        auto k = std::make_shared<Matrix24d>(to_component_major(grid.stiffness(level, e)));
        // The element's nodes get their material's stiffness times a small fraction from the
        // empty part of the cell (the finite cell method's fictitious material), matching the
        // mass floor: a corner far from the element's few voxels otherwise has almost no
        // stiffness and almost no mass, its own fast, undamped mode, and flies off under the
        // corotational forces (seen on the liver at level 3: 35 m/s^2 on a one-voxel element).
        const auto dominant = static_cast<std::size_t>(std::max_element(g.content.begin(), g.content.end(),
            [](const grid::MaterialMoments& a, const grid::MaterialMoments& b) { return a.voxels < b.voxels; })->material);
        *k += k_fictitious_fraction * full[dominant];
        el.stiffness = k.get();
        m_partial_stiffness.push_back(std::move(k));
    }
    el.mass = old ? old->mass : grid.mass(level, e);
    for (int c = 0; c < 8; ++c) {
        el.rest.segment<3>(3 * c) = grid::BranchedGrid::cell_corner_index(g.cell, level, c).cwiseProduct(h);
        m_nodal_mass[el.dof_node[c]] += el.mass.row(c).sum();
    }
    // Centroid of the element's material (first moments over zeroth, summed over materials),
    // in the cell's local coordinates t in [0, 1]^3.
    double q0 = 0.0;
    std::uint32_t voxels = 0, most = 0;
    Eigen::Vector3d q1 = Eigen::Vector3d::Zero();
    for (const grid::MaterialMoments& m : g.content) {
        q0 += static_cast<double>(m.moments[0]);
        voxels += m.voxels;
        q1 += Eigen::Vector3d(static_cast<double>(m.moments[1]), static_cast<double>(m.moments[3]),
                              static_cast<double>(m.moments[9]));
        if (m.voxels > most) {
            most = m.voxels;
            el.material = m.material;
        }
    }
    const Eigen::Vector3d local = q1 / q0 / cell;
    el.gradient = corner_gradients(local, cell * h);
    el.volume_m3 = voxels * h.prod();
    const Eigen::Vector3d centre = grid::BranchedGrid::cell_corner_index(g.cell, level, 0) + cell * local;
    el.centroid = grid.voxels().world_mm(centre) * 1e-3;
    m_elements.push_back(el);
}

void HexModel::add_mass_floor(const grid::BranchedGrid& grid)
{
    const Eigen::Vector3d h = grid.voxels().voxel_size_m();
    double density = 0.0;
    for (const grid::ElasticMaterial& m : grid.materials()) density = std::max(density, m.density_kg_m3);
    m_added_mass.assign(m_nodal_mass.size(), 0.0);
    for (std::size_t n = 0; n < m_nodal_mass.size(); ++n) {
        // A full cell's corner mass at the node's own level.
        const double cell = static_cast<double>(1 << (m_node_level.empty() ? m_level : m_node_level[n]));
        const double floor = k_fictitious_fraction * density * (cell * cell * cell) * h.prod() / 8.0;
        if (m_nodal_mass[n] < floor) {
            m_added_mass[n] = floor - m_nodal_mass[n];
            m_nodal_mass[n] = floor;
        }
    }
}

double HexModel::total_mass() const { return std::accumulate(m_nodal_mass.begin(), m_nodal_mass.end(), 0.0); }

ElementShapes element_shapes(const HexModel& model, const std::vector<Eigen::Vector3d>& positions)
{
    // F = frame^T sum_c x_c (dN_c/dX)^T is I at rest; frame is orthogonal (det +-1), and leaves
    // the Frobenius norm as it is.
    const double orientation = model.frame().determinant();
    ElementShapes out;
    for (const HexElement& el : model.elements()) {
        Eigen::Matrix3d f = Eigen::Matrix3d::Zero();
        Eigen::Vector3d middle = Eigen::Vector3d::Zero();
        for (int c = 0; c < 8; ++c) {
            f += (positions[el.dof_node[c]] - positions[el.dof_node[0]]) * el.gradient.row(c);
            middle += positions[el.dof_node[c]] / 8.0;
        }
        out.add(f, orientation, middle);
    }
    return out;
}

} // namespace vox::fem
