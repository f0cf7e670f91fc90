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
        if (2 * (m_size + 1) > m_keys.size()) rehash(2 * m_size + 2);
        std::size_t s = slot(key);
        if (m_keys[s] == empty) ++m_size;
        m_keys[s] = key;
        m_values[s] = value;
    }
    /// The value of `key`, or `missing`.
    [[nodiscard]] std::uint32_t find(std::uint64_t key) const
    {
        const std::size_t s = slot(key);
        return m_keys[s] == empty ? missing : m_values[s];
    }
    [[nodiscard]] std::size_t size() const { return m_size; }

private:
    static constexpr std::uint64_t empty = ~std::uint64_t{0};

    std::size_t slot(std::uint64_t key) const
    {
        // Fibonacci hashing spreads the structured (Morton or packed) keys over the table.
        std::size_t s = static_cast<std::size_t>((key * 0x9e3779b97f4a7c15ULL) >> m_shift);
        while (m_keys[s] != empty && m_keys[s] != key) s = (s + 1) & (m_keys.size() - 1);
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
        std::vector<std::uint64_t> keys(capacity, empty);
        std::vector<std::uint32_t> values(capacity, missing);
        std::swap(keys, m_keys);
        std::swap(values, m_values);
        m_shift = 64 - bits;
        m_size = 0;
        for (std::size_t i = 0; i < keys.size(); ++i)
            if (keys[i] != empty) insert(keys[i], values[i]);
    }

    std::vector<std::uint64_t> m_keys;
    std::vector<std::uint32_t> m_values;
    std::size_t m_size = 0;
    int m_shift = 60;
};

} // namespace vox::grid
