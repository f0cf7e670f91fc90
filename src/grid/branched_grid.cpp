#include "grid/branched_grid.hpp"

#include "core/error.hpp"
#include "core/memory_usage.hpp"
#include "core/morton.hpp"
#include "grid/condensation.hpp"
#include "grid/union_find.hpp"

#include <algorithm>
#include <chrono>

namespace vox::grid {
namespace {

using Clock = std::chrono::steady_clock;
double ms_since(Clock::time_point t) { return std::chrono::duration<double, std::milli>(Clock::now() - t).count(); }

Coord shift(const Coord& c, int bits) { return {c.x() >> bits, c.y() >> bits, c.z() >> bits}; }

/// Node ids by the closure of face sharing: element e's corner c is slot 8 e + c; an edge joins
/// the four corners of the lower element's +axis face to the matching corners of the upper one.
/// Returns the number of distinct nodes among the slots of elements for which `used(e)` holds.
template <class Used, class Assign>
std::uint64_t number_nodes(std::size_t element_count, const std::vector<Edge>& edges, Used&& used, Assign&& assign)
{
    UnionFind sets(8 * element_count);
    for (const Edge& e : edges)
        for (int c = 0; c < 8; ++c)
            if ((c >> e.axis) & 1) sets.unite(8 * e.lower + c, 8 * e.upper + (c ^ (1 << e.axis)));
    std::vector<std::uint32_t> id(8 * element_count, ~std::uint32_t{0});
    std::uint32_t next = 0;
    for (std::uint32_t e = 0; e < element_count; ++e) {
        if (!used(e)) continue;
        for (int c = 0; c < 8; ++c) {
            const std::uint32_t root = sets.find(8 * e + c);
            if (id[root] == ~std::uint32_t{0}) id[root] = next++;
            assign(e, c, id[root]);
        }
    }
    return next;
}

} // namespace

BranchedGrid::BranchedGrid(FineVoxels voxels, std::vector<VoxelMaterial> materials, int max_level,
                           const Options& options)
    : m_voxels(std::move(voxels)), m_materials(std::move(materials))
{
    if (max_level < 0 || max_level > 6) throw InputError("levels must be 0 .. 6, got " + std::to_string(max_level));
    m_levels.resize(static_cast<std::size_t>(max_level) + 1);
    m_maps.resize(m_levels.size());
    build_level0(options.level0_nodes);
    for (int l = 1; l <= max_level; ++l) build_level(l);
}

void BranchedGrid::build_level0(bool with_nodes)
{
    const auto start = Clock::now();
    Level& level0 = m_levels[0];
    for (std::uint32_t v = 0; v < m_voxels.slots(); ++v) {
        if (!m_voxels.alive(v)) continue;
        for (std::uint8_t axis = 0; axis < 3; ++axis) {
            const std::uint32_t w = m_voxels.connected_neighbour(v, axis);
            if (w != FineVoxels::missing) level0.edges.push_back({v, w, axis});
        }
    }
    std::sort(level0.edges.begin(), level0.edges.end(),
              [](const Edge& a, const Edge& b) { return std::tie(a.lower, a.upper, a.axis) < std::tie(b.lower, b.upper, b.axis); });
    LevelStats& s = level0.stats;
    s.cells = s.elements = m_voxels.alive_count();
    if (with_nodes)
        s.nodes = number_nodes(m_voxels.slots(), level0.edges, [&](std::uint32_t v) { return m_voxels.alive(v); },
                               [](std::uint32_t, int, std::uint32_t) {});
    m_maps[0] = std::make_unique<MomentMatrices>(0, m_voxels.voxel_size_m());
    s.build_ms = ms_since(start);
    s.peak_memory_bytes = peak_memory_bytes();
}

void BranchedGrid::build_level(int l)
{
    const auto start = Clock::now();
    const Level& below = m_levels[static_cast<std::size_t>(l) - 1];
    Level& out = m_levels[static_cast<std::size_t>(l)];
    out.level = l;

    // Children: the voxels for level 1, the elements of level l - 1 otherwise; both are sorted by
    // the Morton code of their cell, so the children of one cell are consecutive.
    const bool from_voxels = l == 1;
    const std::size_t child_count = from_voxels ? m_voxels.slots() : below.elements.size();
    auto child_alive = [&](std::size_t c) { return !from_voxels || m_voxels.alive(static_cast<std::uint32_t>(c)); };
    auto child_code = [&](std::size_t c) {
        return from_voxels ? m_voxels.code(static_cast<std::uint32_t>(c)) : below.elements[c].code;
    };
    auto child_cell = [&](std::size_t c) {
        return from_voxels ? Coord(m_voxels.coord(static_cast<std::uint32_t>(c))) : below.elements[c].cell;
    };

    // Components inside each cell: children joined by an edge that stays within the parent cell.
    UnionFind sets(child_count);
    for (const Edge& e : below.edges)
        if ((child_code(e.lower) >> 3) == (child_code(e.upper) >> 3)) sets.unite(e.lower, e.upper);

    std::vector<std::uint32_t> element_of(child_count, ~std::uint32_t{0});
    std::vector<std::pair<std::uint32_t, std::uint32_t>> roots; // (root child, element) within one cell
    for (std::size_t c = 0; c < child_count;) {
        if (!child_alive(c)) {
            ++c;
            continue;
        }
        const std::uint64_t parent = child_code(c) >> 3;
        roots.clear();
        ++out.stats.cells;
        for (; c < child_count && (child_code(c) >> 3) == parent; ++c) {
            if (!child_alive(c)) continue;
            const std::uint32_t root = sets.find(static_cast<std::uint32_t>(c));
            auto it = std::find_if(roots.begin(), roots.end(), [&](const auto& r) { return r.first == root; });
            if (it == roots.end()) {
                Element e;
                e.cell = shift(child_cell(c), 1);
                e.code = parent;
                roots.emplace_back(root, static_cast<std::uint32_t>(out.elements.size()));
                out.elements.push_back(std::move(e));
                it = roots.end() - 1;
            }
            element_of[c] = it->second;
        }
    }

    // Each element's fine voxels: its children's, in Morton order.
    for (std::size_t c = 0; c < child_count; ++c)
        if (element_of[c] != ~std::uint32_t{0})
            out.elements[element_of[c]].voxel_count += from_voxels ? 1 : below.elements[c].voxel_count;
    std::uint32_t offset = 0;
    for (Element& e : out.elements) {
        e.voxel_begin = offset;
        offset += e.voxel_count;
        e.voxel_count = 0;
    }
    out.voxels.resize(offset);
    for (std::size_t c = 0; c < child_count; ++c) {
        if (element_of[c] == ~std::uint32_t{0}) continue;
        Element& e = out.elements[element_of[c]];
        if (from_voxels) {
            out.voxels[e.voxel_begin + e.voxel_count++] = static_cast<std::uint32_t>(c);
        } else {
            const Element& child = below.elements[c];
            std::copy_n(below.voxels.begin() + child.voxel_begin, child.voxel_count,
                        out.voxels.begin() + e.voxel_begin + e.voxel_count);
            e.voxel_count += child.voxel_count;
        }
    }

    // Direct condensation: each maximal full one-material Morton interval adds its box moments.
    const std::uint64_t local_mask = (std::uint64_t{1} << (3 * l)) - 1;
    std::vector<CellVoxel> cell_voxels;
    for (Element& e : out.elements) {
        auto first = out.voxels.begin() + e.voxel_begin;
        auto last = first + e.voxel_count;
        if (!std::is_sorted(first, last)) std::sort(first, last); // superimposed children interleave
        cell_voxels.clear();
        for (auto it = first; it != last; ++it)
            cell_voxels.push_back({m_voxels.code(*it) & local_mask, m_voxels.material(*it)});
        for (const SubNode& s : full_subnodes(cell_voxels, l)) {
            const Eigen::Vector3i origin(static_cast<int>(morton_decode_axis(s.first, 0)),
                                         static_cast<int>(morton_decode_axis(s.first, 1)),
                                         static_cast<int>(morton_decode_axis(s.first, 2)));
            auto it = std::lower_bound(e.content.begin(), e.content.end(), s.material,
                                       [](const MaterialMoments& m, std::int32_t mat) { return m.material < mat; });
            if (it == e.content.end() || it->material != s.material)
                it = e.content.insert(it, MaterialMoments{s.material, 0, {}});
            add_box_moments(it->moments, origin, 1 << s.level);
            it->voxels += 1u << (3 * s.level);
            ++out.stats.condensation_steps_direct;
        }
        out.stats.condensation_steps_recursive += recursive_step_count(cell_voxels, l);
    }

    // Edges between elements of different cells come from the child edges that cross cells.
    for (const Edge& e : below.edges)
        if ((child_code(e.lower) >> 3) != (child_code(e.upper) >> 3))
            out.edges.push_back({element_of[e.lower], element_of[e.upper], e.axis});
    std::sort(out.edges.begin(), out.edges.end(),
              [](const Edge& a, const Edge& b) { return std::tie(a.lower, a.upper, a.axis) < std::tie(b.lower, b.upper, b.axis); });
    out.edges.erase(std::unique(out.edges.begin(), out.edges.end()), out.edges.end());

    out.stats.elements = out.elements.size();
    out.stats.nodes = number_nodes(out.elements.size(), out.edges, [](std::uint32_t) { return true; },
                                   [&](std::uint32_t e, int c, std::uint32_t id) { out.elements[e].nodes[c] = id; });
    m_maps[static_cast<std::size_t>(l)] = std::make_unique<MomentMatrices>(l, m_voxels.voxel_size_m());
    out.stats.build_ms = ms_since(start);
    out.stats.peak_memory_bytes = peak_memory_bytes();
}

Matrix24d BranchedGrid::stiffness(int l, std::uint32_t e) const
{
    return m_maps.at(static_cast<std::size_t>(l))->stiffness(level(l).elements.at(e).content, m_materials);
}

Matrix8d BranchedGrid::mass(int l, std::uint32_t e) const
{
    return m_maps.at(static_cast<std::size_t>(l))->mass(level(l).elements.at(e).content, m_materials);
}

double BranchedGrid::total_mass_kg() const
{
    double total = 0.0;
    const double volume = m_voxels.voxel_size_m().prod();
    for (std::uint32_t v = 0; v < m_voxels.slots(); ++v)
        if (m_voxels.alive(v)) total += m_materials[static_cast<std::size_t>(m_voxels.material(v))].density_kg_m3 * volume;
    return total;
}

} // namespace vox::grid
