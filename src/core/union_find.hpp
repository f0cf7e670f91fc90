#pragma once
// Disjoint sets over 0 .. n-1 with path halving and union by index (the smaller index becomes the
// root, which makes the result independent of the order of unions for the same final sets).

#include <cstdint>
#include <numeric>
#include <vector>

namespace vox {

class UnionFind {
public:
    explicit UnionFind(std::size_t n) : m_parent(n) { std::iota(m_parent.begin(), m_parent.end(), std::uint32_t{0}); }

    [[nodiscard]] std::uint32_t find(std::uint32_t x)
    {
        while (m_parent[x] != x) {
            m_parent[x] = m_parent[m_parent[x]];
            x = m_parent[x];
        }
        return x;
    }
    void unite(std::uint32_t a, std::uint32_t b)
    {
        a = find(a);
        b = find(b);
        if (a == b) return;
        if (a < b)
            m_parent[b] = a;
        else
            m_parent[a] = b;
    }

private:
    std::vector<std::uint32_t> m_parent;
};

} // namespace vox
