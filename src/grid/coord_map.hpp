#pragma once
// A compact open-addressing hash map from packed keys (64-bit, never ~0) to 32-bit indices, for
// the millions of voxel and cell lookups of the grid builds (std::unordered_map allocates per
// entry and is several times slower here).

#include <cstdint>
#include <vector>

namespace vox::grid {

class CoordMap {
public:
    static constexpr std::uint32_t missing = ~std::uint32_t{0};

    /// Room for `expected` keys at a load factor of at most 1/2.
    explicit CoordMap(std::size_t expected = 0) { rehash(expected); }

    /// Inserts key -> value, or overwrites the value of an existing key.
    void insert(std::uint64_t key, std::uint32_t value)
    {
        if (2 * (m_size + 1) > m_slots.size()) rehash(2 * m_size + 2);
        Slot& s = m_slots[slot(key)];
        if (s.key == empty) ++m_size;
        s = {key, value};
    }
    /// The value of `key`, or `missing`.
    [[nodiscard]] std::uint32_t find(std::uint64_t key) const
    {
        const Slot& s = m_slots[slot(key)];
        return s.key == empty ? missing : s.value;
    }
    [[nodiscard]] std::size_t size() const { return m_size; }

private:
    static constexpr std::uint64_t empty = ~std::uint64_t{0};

    /// Key and value side by side: one cache line per lookup.
    struct Slot {
        std::uint64_t key = empty;
        std::uint32_t value = missing;
    };

    std::size_t slot(std::uint64_t key) const
    {
        // Fibonacci hashing spreads the structured (Morton or packed) keys over the table.
        std::size_t s = static_cast<std::size_t>((key * 0x9e3779b97f4a7c15ULL) >> m_shift);
        while (m_slots[s].key != empty && m_slots[s].key != key) s = (s + 1) & (m_slots.size() - 1);
        return s;
    }
    void rehash(std::size_t expected)
    {
        std::size_t capacity = 16;
        int bits = 4;
        while (capacity < 2 * expected) {
            capacity *= 2;
            ++bits;
        }
        std::vector<Slot> old(capacity);
        std::swap(old, m_slots);
        m_shift = 64 - bits;
        m_size = 0;
        for (const Slot& s : old)
            if (s.key != empty) insert(s.key, s.value);
    }

    std::vector<Slot> m_slots;
    std::size_t m_size = 0;
    int m_shift = 60;
};

} // namespace vox::grid
