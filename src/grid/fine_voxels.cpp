#include "grid/fine_voxels.hpp"

#include "core/error.hpp"
#include "core/memory_limit.hpp"
#include "core/morton.hpp"

#include <algorithm>
#include <numeric>

namespace vox::grid {
namespace {
constexpr int k_max_extent = 1 << 21;
}

FineVoxels::FineVoxels(const LabelGrid& labels, const std::function<std::int32_t(std::int32_t)>& material_of)
    : m_index_to_world(labels.index_to_world()), m_voxel_size_m(labels.voxel_size() * 1e-3)
{
    const IndexBox box = labels.index_bounds();
    if (box.empty()) throw InputError("the object holds no voxel");
    // Floor to a multiple of 64 (arithmetic shift floors negative indices too).
    m_origin = Coord((box.min.x() >> 6) << 6, (box.min.y() >> 6) << 6, (box.min.z() >> 6) << 6);
    if (((box.max - m_origin).array() >= k_max_extent).any())
        throw InputError("the object spans more than 2^21 voxels along an axis");

    // About 64 bytes per voxel for the fine level (index, neighbours, codes), more for the levels.
    check_allocation("the object's fine voxels", labels.active_voxel_count(), 64);
    struct Entry {
        std::uint64_t code;
        Coord ijk;
        std::int32_t label;
    };
    std::vector<Entry> entries;
    entries.reserve(labels.active_voxel_count());
    labels.for_each_active([&](const Coord& c, std::int32_t label) {
        const Coord l = c - m_origin;
        entries.push_back({morton_encode(l.x(), l.y(), l.z()), c, label});
    });
    std::sort(entries.begin(), entries.end(), [](const Entry& a, const Entry& b) { return a.code < b.code; });

    const std::size_t n = entries.size();
    m_codes.resize(n);
    m_coords.resize(n);
    m_labels.resize(n);
    m_materials.resize(n);
    m_alive.assign(n, 1);
    m_alive_count = static_cast<std::uint32_t>(n);
    m_bricks = CoordMap(n / 64 + 16);
    for (std::size_t v = 0; v < n; ++v) {
        m_codes[v] = entries[v].code;
        m_coords[v] = entries[v].ijk;
        m_labels[v] = entries[v].label;
        m_materials[v] = material_of(entries[v].label);
        const std::uint64_t brick_code = entries[v].code >> 9;
        std::uint32_t brick = m_bricks.find(brick_code);
        if (brick == CoordMap::missing) {
            brick = static_cast<std::uint32_t>(m_brick_slots.size() >> 9);
            m_bricks.insert(brick_code, brick);
            m_brick_slots.resize(m_brick_slots.size() + 512, missing);
        }
        m_brick_slots[(std::size_t{brick} << 9) | (entries[v].code & 511)] = static_cast<std::uint32_t>(v);
    }
    // Neighbour slots once, so that connectivity queries never hash again.
    m_neighbours.assign(n, {missing, missing, missing, missing, missing, missing});
    for (std::uint32_t v = 0; v < n; ++v)
        for (int axis = 0; axis < 3; ++axis) {
            Coord up = m_coords[v];
            ++up[axis];
            const std::uint32_t w = find(up);
            if (w == missing) continue;
            m_neighbours[v][2 * axis + 1] = w;
            m_neighbours[w][2 * axis] = v;
        }
}

std::uint64_t FineVoxels::key(const Coord& ijk) const
{
    const Coord l = ijk - m_origin;
    if ((l.array() < 0).any() || (l.array() >= k_max_extent).any()) return ~std::uint64_t{0} - 1;
    return morton_encode(l.x(), l.y(), l.z());
}

std::uint32_t FineVoxels::find(const Coord& ijk) const
{
    const std::uint32_t v = slot_of(key(ijk));
    return (v != missing && m_alive[v]) ? v : missing;
}

std::uint32_t FineVoxels::find_code(std::uint64_t code) const
{
    const std::uint32_t v = slot_of(code);
    return (v != missing && m_alive[v]) ? v : missing;
}

std::uint32_t FineVoxels::connected_neighbour(std::uint32_t v, int axis) const
{
    const std::uint32_t w = m_neighbours[v][2 * axis + 1];
    return (w == missing || face_disconnected(v, axis)) ? missing : w;
}

void FineVoxels::remove(std::uint32_t v)
{
    if (!m_alive[v]) return;
    m_alive[v] = 0;
    --m_alive_count;
    for (int d = 0; d < 6; ++d) {
        const std::uint32_t w = m_neighbours[v][d];
        if (w != missing) m_neighbours[w][d ^ 1] = missing;
        m_neighbours[v][d] = missing;
    }
}

void FineVoxels::disconnect(std::uint32_t v, int axis) { m_disconnected.insert(4 * std::uint64_t{v} + axis); }

} // namespace vox::grid
