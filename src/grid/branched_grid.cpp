#include "grid/branched_grid.hpp"

#include "core/error.hpp"
#include "core/memory_usage.hpp"
#include "core/progress.hpp"
#include "core/morton.hpp"
#include "grid/condensation.hpp"
#include "grid/hex8.hpp"
#include "core/union_find.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>

namespace vox::grid {
namespace {

using Clock = std::chrono::steady_clock;
double ms_since(Clock::time_point t) { return std::chrono::duration<double, std::milli>(Clock::now() - t).count(); }

Coord shift(const Coord& c, int bits) { return {c.x() >> bits, c.y() >> bits, c.z() >> bits}; }

Eigen::Vector3i decode(std::uint64_t code)
{
    return {static_cast<int>(morton_decode_axis(code, 0)), static_cast<int>(morton_decode_axis(code, 1)),
            static_cast<int>(morton_decode_axis(code, 2))};
}

/// Index of fine voxel v inside its level-l cell.
Eigen::Vector3i local_index(const FineVoxels& fine, std::uint32_t v, int l)
{
    return decode(fine.code(v) & ((std::uint64_t{1} << (3 * l)) - 1));
}

std::uint64_t encode(const Eigen::Vector3i& c)
{
    return morton_encode(static_cast<std::uint32_t>(c.x()), static_cast<std::uint32_t>(c.y()),
                         static_cast<std::uint32_t>(c.z()));
}

void sort_unique(std::vector<std::uint64_t>& v)
{
    std::sort(v.begin(), v.end());
    v.erase(std::unique(v.begin(), v.end()), v.end());
}

struct Condensed {
    ElementContent content;
    std::uint64_t steps_direct = 0;
    std::uint64_t steps_recursive = 0;
};

/// The paper's direct condensation into exact moments: each maximal full one-material Morton
/// interval of the element's voxels adds its box moments in one step.
Condensed condense(const FineVoxels& fine, int l, const std::vector<std::uint32_t>& voxels, bool count_recursive)
{
    const std::uint64_t local_mask = (std::uint64_t{1} << (3 * l)) - 1;
    std::vector<CellVoxel> cell;
    cell.reserve(voxels.size());
    for (std::uint32_t v : voxels) cell.push_back({fine.code(v) & local_mask, fine.material(v)});
    Condensed out;
    for (const SubNode& s : full_subnodes(cell, l)) {
        auto it = std::lower_bound(out.content.begin(), out.content.end(), s.material,
                                   [](const MaterialMoments& m, std::int32_t mat) { return m.material < mat; });
        if (it == out.content.end() || it->material != s.material)
            it = out.content.insert(it, MaterialMoments{s.material, 0, {}});
        add_box_moments(it->moments, decode(s.first), 1 << s.level);
        it->voxels += 1u << (3 * s.level);
        ++out.steps_direct;
    }
    if (count_recursive) out.steps_recursive = recursive_step_count(cell, l);
    return out;
}

} // namespace

std::vector<std::uint32_t> Level::cell_elements(std::uint64_t code) const
{
    std::vector<std::uint32_t> out;
    for (std::uint32_t e = cells.find(code); e != no_index; e = elements[e].next_in_cell) out.push_back(e);
    return out;
}

BranchedGrid::BranchedGrid(FineVoxels voxels, std::vector<ElasticMaterial> materials, int max_level,
                           const Options& options)
    : m_voxels(std::move(voxels)), m_materials(std::move(materials))
{
    if (max_level < 0 || max_level > 6) throw InputError("levels must be 0 .. 6, got " + std::to_string(max_level));
    m_levels.resize(static_cast<std::size_t>(max_level) + 1);
    m_maps.resize(m_levels.size());
    m_full_stiffness.resize(m_levels.size());
    m_full_mass.resize(m_levels.size());
    for (std::size_t l = 0; l < m_levels.size(); ++l) {
        m_levels[l].level = static_cast<int>(l);
        m_maps[l] = std::make_unique<MomentMatrices>(static_cast<int>(l), m_voxels.voxel_size_m());
        // Equations 2 and 3: a full cell of level l is the voxel element scaled by 2^l (K), 2^3l (M).
        const double s = static_cast<double>(1 << l);
        for (const ElasticMaterial& m : m_materials) {
            m_full_stiffness[l].push_back(s * hex8_stiffness(m_voxels.voxel_size_m(), m.lame));
            m_full_mass[l].push_back(s * s * s * hex8_mass(m_voxels.voxel_size_m(), m.density_kg_m3));
        }
    }
    build_level0(options.level0_nodes);
    std::vector<std::uint64_t> cells;
    cells.reserve(m_voxels.alive_count());
    for (std::uint32_t v = 0; v < m_voxels.slots(); ++v)
        if (m_voxels.alive(v)) cells.push_back(m_voxels.code(v) >> 3);
    sort_unique(cells);
    Progress progress("building the branched grid", static_cast<std::uint64_t>(max_level));
    for (int l = 1; l <= max_level; ++l) {
        progress.update(static_cast<std::uint64_t>(l - 1));
        const auto start = Clock::now();
        m_levels[static_cast<std::size_t>(l)].cells = CoordMap(cells.size());
        rebuild_cells(l, cells, true);
        LevelStats& s = m_levels[static_cast<std::size_t>(l)].stats;
        s.build_ms = ms_since(start);
        s.peak_memory_bytes = peak_memory_bytes();
        for (auto& c : cells) c >>= 3;
        sort_unique(cells);
    }
}

void BranchedGrid::build_level0(bool with_nodes)
{
    const auto start = Clock::now();
    LevelStats& s = m_levels[0].stats;
    s.cells = s.elements = m_voxels.alive_count();
    if (with_nodes) {
        // Slot 8 v + c is corner c of voxel v; a connected +axis face joins four corner pairs.
        UnionFind sets(8 * std::size_t{m_voxels.slots()});
        for (std::uint32_t v = 0; v < m_voxels.slots(); ++v) {
            if (!m_voxels.alive(v)) continue;
            for (int axis = 0; axis < 3; ++axis) {
                const std::uint32_t w = m_voxels.connected_neighbour(v, axis);
                if (w == FineVoxels::missing) continue;
                for (int c = 0; c < 8; ++c)
                    if ((c >> axis) & 1) sets.unite(8 * v + c, 8 * w + (c ^ (1 << axis)));
            }
        }
        for (std::uint32_t v = 0; v < m_voxels.slots(); ++v)
            if (m_voxels.alive(v))
                for (int c = 0; c < 8; ++c) s.nodes += sets.find(8 * v + c) == 8 * v + c;
    }
    s.build_ms = ms_since(start);
    s.peak_memory_bytes = peak_memory_bytes();
}

LevelChange BranchedGrid::rebuild_cells(int l, std::vector<std::uint64_t> cell_codes, bool initial)
{
    Level& out = m_levels[static_cast<std::size_t>(l)];
    const Level& below = m_levels[static_cast<std::size_t>(l) - 1];
    const bool from_voxels = l == 1;
    LevelChange change;

    // Children of a cell and their links, at the level below (voxels for level 1).
    auto children_of = [&](std::uint64_t cell, std::vector<std::uint32_t>& children) {
        children.clear();
        for (std::uint64_t o = 0; o < 8; ++o) {
            const std::uint64_t code = cell << 3 | o;
            if (from_voxels) {
                const std::uint32_t v = m_voxels.find_code(code);
                if (v != FineVoxels::missing) children.push_back(v);
            } else {
                for (std::uint32_t e = below.cells.find(code); e != no_index; e = below.elements[e].next_in_cell)
                    children.push_back(e);
            }
        }
    };
    auto child_code = [&](std::uint32_t c) { return from_voxels ? m_voxels.code(c) : below.elements[c].code; };
    auto child_alive = [&](std::uint32_t c) { return from_voxels ? m_voxels.alive(c) : below.elements[c].alive; };
    auto for_each_child_link = [&](std::uint32_t c, auto&& f) {
        if (from_voxels)
            m_voxels.for_each_link(c, [&](std::uint32_t t, int dir) { f(t, dir); });
        else
            for (const Link& link : below.elements[c].links) f(link.element, link.direction);
    };
    auto append_child_voxels = [&](std::uint32_t c, std::vector<std::uint32_t>& voxels) {
        if (from_voxels)
            voxels.push_back(c);
        else
            voxels.insert(voxels.end(), below.elements[c].voxels.begin(), below.elements[c].voxels.end());
    };

    if (out.parent.size() < (from_voxels ? m_voxels.slots() : below.elements.size()))
        out.parent.resize(from_voxels ? m_voxels.slots() : below.elements.size(), no_index);

    std::vector<std::uint32_t> touched;   // elements whose links must be recomputed
    std::vector<std::uint32_t> children;
    std::vector<std::uint32_t> component;
    for (std::uint64_t cell : cell_codes) {
        const std::vector<std::uint32_t> old = initial ? std::vector<std::uint32_t>{} : out.cell_elements(cell);
        for (std::uint32_t e : old)
            for (const Link& link : out.elements[e].links) touched.push_back(link.element);

        // Components of the cell's children through links that stay inside the cell.
        children_of(cell, children);
        UnionFind sets(children.size());
        for (std::size_t i = 0; i < children.size(); ++i)
            for_each_child_link(children[i], [&](std::uint32_t t, int) {
                if ((child_code(t) >> 3) != cell) return;
                const auto j = std::find(children.begin(), children.end(), t) - children.begin();
                sets.unite(static_cast<std::uint32_t>(i), static_cast<std::uint32_t>(j));
            });

        std::vector<std::uint32_t> kept;
        std::uint32_t head = no_index, tail = no_index;
        for (std::size_t i = 0; i < children.size(); ++i) {
            if (sets.find(static_cast<std::uint32_t>(i)) != i) continue; // not the first child of its component
            component.clear();
            for (std::size_t j = i; j < children.size(); ++j)
                if (sets.find(static_cast<std::uint32_t>(j)) == i) component.push_back(children[j]);
            std::sort(component.begin(), component.end());

            // An old element whose surviving children are exactly these keeps its id: no topology
            // change, so its content only loses the removed voxels' moments (equation 5).
            std::uint32_t id = no_index;
            for (std::uint32_t e : old) {
                const auto& before = out.elements[e].children;
                std::size_t surviving = 0;
                bool same = true;
                for (std::uint32_t c : before) {
                    if (!child_alive(c)) continue;
                    same = same && surviving < component.size() && component[surviving] == c;
                    ++surviving;
                }
                if (same && surviving == component.size()) id = e;
            }
            // A child that died may live on as a new child elsewhere (a split below): keeping the
            // id needs the surviving voxels to be exactly those of these children.
            if (id != no_index) {
                std::size_t expect = 0, alive = 0;
                for (std::uint32_t c : component) expect += from_voxels ? 1 : below.elements[c].voxels.size();
                for (std::uint32_t v : out.elements[id].voxels) alive += m_voxels.alive(v);
                if (alive != expect) id = no_index;
            }
            if (id != no_index) {
                kept.push_back(id);
                Element& e = out.elements[id];
                const std::size_t before = e.voxels.size();
                std::erase_if(e.voxels, [&](std::uint32_t v) {
                    if (m_voxels.alive(v)) return false;
                    update_content(e.content, m_voxels.material(v), local_index(m_voxels, v, l), -1);
                    return true;
                });
                if (e.voxels.size() != before) change.updated.push_back(id);
            } else {
                std::vector<std::uint32_t> voxels;
                for (std::uint32_t c : component) append_child_voxels(c, voxels);
                if (!std::is_sorted(voxels.begin(), voxels.end())) std::sort(voxels.begin(), voxels.end());
                std::vector<std::uint32_t> came_from;
                for (std::uint32_t e : old)
                    if (std::any_of(voxels.begin(), voxels.end(), [&](std::uint32_t v) {
                            return std::binary_search(out.elements[e].voxels.begin(), out.elements[e].voxels.end(), v);
                        }))
                        came_from.push_back(e);
                if (!out.free_elements.empty()) {
                    id = out.free_elements.back();
                    out.free_elements.pop_back();
                } else {
                    id = static_cast<std::uint32_t>(out.elements.size());
                    out.elements.emplace_back();
                }
                if (!initial) change.created.emplace_back(id, std::move(came_from));
                Element& e = out.elements[id];
                e.alive = true;
                e.nodes.fill(no_index);
                const Condensed c = condense(m_voxels, l, voxels, initial);
                e.content = c.content;
                out.stats.condensation_steps_direct += initial ? c.steps_direct : 0;
                out.stats.condensation_steps_recursive += initial ? c.steps_recursive : 0;
                e.voxels = std::move(voxels);
                ++out.stats.elements;
            }
            Element& e = out.elements[id];
            e.code = cell;
            e.cell = shift(from_voxels ? m_voxels.coord(component.front()) : below.elements[component.front()].cell, 1);
            e.children = component;
            for (std::uint32_t c : component) out.parent[c] = id;
            e.next_in_cell = no_index;
            if (head == no_index)
                head = id;
            else
                out.elements[tail].next_in_cell = id;
            tail = id;
            touched.push_back(id);
        }
        // Old elements that were not kept are removed (cell removal or split).
        for (std::uint32_t e : old) {
            if (std::find(kept.begin(), kept.end(), e) != kept.end()) continue;
            Element& dead = out.elements[e];
            for (std::uint32_t n : dead.nodes)
                if (n != no_index && --out.node_users[n] == 0) {
                    out.free_nodes.push_back(n);
                    --out.stats.nodes;
                }
            dead = Element{};
            out.released_elements.push_back(e);
            change.removed.push_back(e);
            --out.stats.elements;
        }
        if (old.empty() && head != no_index) ++out.stats.cells;
        if (!old.empty() && head == no_index) --out.stats.cells;
        out.cells.insert(cell, head);
    }

    // Links of every element built here and of every neighbour that linked to an old element:
    // the parents of the children's links that leave the cell.
    std::sort(touched.begin(), touched.end());
    touched.erase(std::unique(touched.begin(), touched.end()), touched.end());
    for (std::uint32_t id : touched) {
        Element& e = out.elements[id];
        if (!e.alive) continue;
        e.links.clear();
        for (std::uint32_t c : e.children)
            for_each_child_link(c, [&](std::uint32_t t, int dir) {
                if ((child_code(t) >> 3) != e.code) e.links.push_back({out.parent[t], static_cast<std::uint8_t>(dir)});
            });
        std::sort(e.links.begin(), e.links.end(),
                  [](const Link& a, const Link& b) { return std::tie(a.element, a.direction) < std::tie(b.element, b.direction); });
        e.links.erase(std::unique(e.links.begin(), e.links.end()), e.links.end());
    }
    if (initial)
        number_all_nodes(l);
    else
        renumber_nodes(l, cell_codes);
    return change;
}

void BranchedGrid::number_all_nodes(int l)
{
    // Slot 8 e + c is corner c of element e; a link joins the four corners of the shared face.
    Level& out = m_levels[static_cast<std::size_t>(l)];
    UnionFind sets(8 * out.elements.size());
    for (std::uint32_t e = 0; e < out.elements.size(); ++e)
        for (const Link& link : out.elements[e].links) {
            if (!(link.direction & 1)) continue; // each link is seen from both sides; take the lower one
            const int axis = link.direction / 2;
            for (int c = 0; c < 8; ++c)
                if ((c >> axis) & 1) sets.unite(8 * e + c, 8 * link.element + (c ^ (1 << axis)));
        }
    std::vector<std::uint32_t> id(8 * out.elements.size(), no_index);
    for (std::uint32_t e = 0; e < out.elements.size(); ++e)
        for (int c = 0; c < 8; ++c) {
            const std::uint32_t root = sets.find(8 * e + c);
            if (id[root] == no_index) {
                id[root] = static_cast<std::uint32_t>(out.node_users.size());
                out.node_users.push_back(0);
            }
            out.elements[e].nodes[c] = id[root];
            ++out.node_users[id[root]];
        }
    out.stats.nodes = out.node_users.size();
}

void BranchedGrid::renumber_nodes(int l, const std::vector<std::uint64_t>& cell_codes)
{
    Level& out = m_levels[static_cast<std::size_t>(l)];
    // The grid vertices whose node classes may have changed: the corners of the rebuilt cells.
    std::vector<std::uint64_t> vertices;
    vertices.reserve(8 * cell_codes.size());
    for (std::uint64_t cell : cell_codes) {
        const Eigen::Vector3i c = decode(cell);
        for (int b = 0; b < 8; ++b) vertices.push_back(encode(c + Eigen::Vector3i(b & 1, (b >> 1) & 1, (b >> 2) & 1)));
    }
    sort_unique(vertices);

    struct Slot {
        std::uint32_t element;
        int corner;
    };
    std::vector<Slot> slots;
    std::vector<std::uint32_t> taken;
    for (std::uint64_t vertex : vertices) {
        const Eigen::Vector3i x = decode(vertex);
        slots.clear();
        for (int b = 0; b < 8; ++b) {
            const Eigen::Vector3i cell = x - Eigen::Vector3i(b & 1, (b >> 1) & 1, (b >> 2) & 1);
            if ((cell.array() < 0).any()) continue;
            for (std::uint32_t e = out.cells.find(encode(cell)); e != no_index; e = out.elements[e].next_in_cell)
                slots.push_back({e, b});
        }
        // Two corners at this vertex are one node when their elements are linked across a face
        // that contains the vertex.
        UnionFind sets(slots.size());
        for (std::size_t i = 0; i < slots.size(); ++i)
            for (const Link& link : out.elements[slots[i].element].links) {
                const int axis = link.direction / 2;
                const bool up = link.direction & 1;
                if (((slots[i].corner >> axis) & 1) != static_cast<int>(up)) continue;
                const int other = slots[i].corner ^ (1 << axis);
                for (std::size_t j = 0; j < slots.size(); ++j)
                    if (slots[j].element == link.element && slots[j].corner == other)
                        sets.unite(static_cast<std::uint32_t>(i), static_cast<std::uint32_t>(j));
            }
        // Each class keeps the smallest old id of its members that no other class here took.
        taken.clear();
        for (std::size_t i = 0; i < slots.size(); ++i) {
            if (sets.find(static_cast<std::uint32_t>(i)) != i) continue;
            std::uint32_t id = no_index;
            for (std::size_t j = i; j < slots.size(); ++j) {
                if (sets.find(static_cast<std::uint32_t>(j)) != i) continue;
                const std::uint32_t old = out.elements[slots[j].element].nodes[slots[j].corner];
                if (old != no_index && old < id && std::find(taken.begin(), taken.end(), old) == taken.end()) id = old;
            }
            if (id == no_index) {
                if (!out.free_nodes.empty()) {
                    id = out.free_nodes.back();
                    out.free_nodes.pop_back();
                } else {
                    id = static_cast<std::uint32_t>(out.node_users.size());
                    out.node_users.push_back(0);
                }
            }
            taken.push_back(id);
            for (std::size_t j = i; j < slots.size(); ++j) {
                if (sets.find(static_cast<std::uint32_t>(j)) != i) continue;
                std::uint32_t& n = out.elements[slots[j].element].nodes[slots[j].corner];
                if (n == id) continue;
                if (n != no_index && --out.node_users[n] == 0) {
                    out.free_nodes.push_back(n);
                    --out.stats.nodes;
                }
                if (out.node_users[id]++ == 0) ++out.stats.nodes;
                n = id;
            }
        }
    }
}

UpdateReport BranchedGrid::update(std::span<const Coord> removed, std::span<const std::pair<Coord, int>> faces)
{
    std::vector<std::uint64_t> cells;
    for (const Coord& c : removed) {
        const std::uint32_t v = m_voxels.find(c);
        if (v == FineVoxels::missing) continue;
        m_voxels.remove(v);
        cells.push_back(m_voxels.code(v) >> 3);
    }
    for (const auto& [c, axis] : faces) {
        const std::uint32_t v = m_voxels.find(c);
        const std::uint32_t w = m_voxels.find(c + Coord::Unit(axis));
        if (v == FineVoxels::missing || w == FineVoxels::missing) continue;
        m_voxels.disconnect(v, axis);
        cells.push_back(m_voxels.code(v) >> 3);
        cells.push_back(m_voxels.code(w) >> 3);
    }
    m_levels[0].stats.cells = m_levels[0].stats.elements = m_voxels.alive_count();
    UpdateReport report;
    report.levels.resize(m_levels.size());
    for (int l = 1; l <= max_level(); ++l) {
        sort_unique(cells);
        report.levels[static_cast<std::size_t>(l)] = rebuild_cells(l, cells, false);
        for (auto& c : cells) c >>= 3;
    }
    // Ids of removed elements become reusable only now: within one update an id means one element.
    for (Level& level : m_levels) {
        level.free_elements.insert(level.free_elements.end(), level.released_elements.begin(),
                                   level.released_elements.end());
        level.released_elements.clear();
    }
    return report;
}

bool BranchedGrid::is_full(int l, std::uint32_t e) const
{
    const ElementContent& c = level(l).elements.at(e).content;
    return c.size() == 1 && c[0].voxels == (1u << (3 * l));
}

Matrix24d BranchedGrid::stiffness(int l, std::uint32_t e) const
{
    const auto lu = static_cast<std::size_t>(l);
    const ElementContent& c = level(l).elements.at(e).content;
    if (is_full(l, e)) return m_full_stiffness[lu][static_cast<std::size_t>(c[0].material)];
    return m_maps.at(lu)->stiffness(c, m_materials);
}

Matrix8d BranchedGrid::mass(int l, std::uint32_t e) const
{
    const auto lu = static_cast<std::size_t>(l);
    const ElementContent& c = level(l).elements.at(e).content;
    if (is_full(l, e)) return m_full_mass[lu][static_cast<std::size_t>(c[0].material)];
    return m_maps.at(lu)->mass(c, m_materials);
}

std::uint32_t BranchedGrid::element_of(std::uint32_t v, int l) const
{
    std::uint32_t e = v;
    for (int k = 1; k <= l; ++k) e = m_levels[static_cast<std::size_t>(k)].parent[e];
    return e;
}

Eigen::Vector3d BranchedGrid::cell_corner_index(const Coord& cell, int l, int c)
{
    const double size = static_cast<double>(1 << l);
    return {(cell.x() + (c & 1)) * size - 0.5, (cell.y() + ((c >> 1) & 1)) * size - 0.5,
            (cell.z() + ((c >> 2) & 1)) * size - 0.5};
}

std::vector<Eigen::Vector3d> BranchedGrid::rest_node_positions(int l) const
{
    const Level& lv = level(l);
    std::vector<Eigen::Vector3d> out(lv.node_users.size(), Eigen::Vector3d::Constant(std::nan("")));
    for (const Element& e : lv.elements) {
        if (!e.alive) continue;
        for (int c = 0; c < 8; ++c)
            out[e.nodes[c]] = m_voxels.world_mm(cell_corner_index(e.cell, l, c));
    }
    return out;
}

double BranchedGrid::total_mass_kg() const
{
    double total = 0.0;
    const double volume = m_voxels.voxel_size_m().prod();
    for (std::uint32_t v = 0; v < m_voxels.slots(); ++v)
        if (m_voxels.alive(v)) total += m_materials[static_cast<std::size_t>(m_voxels.material(v))].density_kg_m3 * volume;
    return total;
}

BranchedGrid::BranchedGrid(const BranchedGrid& other)
    : m_voxels(other.m_voxels), m_materials(other.m_materials), m_levels(other.m_levels), m_full_stiffness(other.m_full_stiffness),
      m_full_mass(other.m_full_mass)
{
    for (const auto& map : other.m_maps) m_maps.push_back(map ? std::make_unique<MomentMatrices>(*map) : nullptr);
}

} // namespace vox::grid
