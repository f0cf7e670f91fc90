#include "grid/condensation.hpp"

#include "core/morton.hpp"

#include <map>

namespace vox::grid {
namespace {

Eigen::Vector3i decode(std::uint64_t code)
{
    return {static_cast<int>(morton_decode_axis(code, 0)), static_cast<int>(morton_decode_axis(code, 1)),
            static_cast<int>(morton_decode_axis(code, 2))};
}

/// target += (h (x) I3)^T k (h (x) I3), using the Kronecker structure (2 x 4608 multiply-adds).
void add_congruence(Matrix24d& target, const Matrix8d& h, const Matrix24d& k)
{
    Matrix24d t;
    for (int r = 0; r < 24; ++r)
        for (int d = 0; d < 8; ++d)
            for (int j = 0; j < 3; ++j) {
                double s = 0.0;
                for (int c = 0; c < 8; ++c) s += k(r, 3 * c + j) * h(c, d);
                t(r, 3 * d + j) = s;
            }
    for (int b = 0; b < 8; ++b)
        for (int i = 0; i < 3; ++i)
            for (int col = 0; col < 24; ++col) {
                double s = 0.0;
                for (int a = 0; a < 8; ++a) s += h(a, b) * t(3 * a + i, col);
                target(3 * b + i, col) += s;
            }
}

struct VoxelMatrices {
    Matrix24d stiffness;
    Matrix8d mass;
};

std::vector<VoxelMatrices> voxel_matrices(const Eigen::Vector3d& voxel_size_m, std::span<const ElasticMaterial> materials)
{
    std::vector<VoxelMatrices> out;
    out.reserve(materials.size());
    for (const ElasticMaterial& m : materials)
        out.push_back({hex8_stiffness(voxel_size_m, m.lame), hex8_mass(voxel_size_m, m.density_kg_m3)});
    return out;
}

} // namespace

std::vector<SubNode> full_subnodes(std::span<const CellVoxel> v, int cell_level, int dimensions)
{
    const std::size_t n = v.size();
    // run_end[p]: one past the last index of the run of consecutive codes of one material from p.
    std::vector<std::size_t> run_end(n);
    for (std::size_t p = n; p-- > 0;)
        run_end[p] = (p + 1 < n && v[p + 1].morton == v[p].morton + 1 && v[p + 1].material == v[p].material)
                         ? run_end[p + 1]
                         : p + 1;
    std::vector<SubNode> out;
    for (std::size_t p = 0; p < n;) {
        int level = cell_level;
        for (; level > 0; --level) {
            const std::uint64_t size = std::uint64_t{1} << (dimensions * level);
            if (v[p].morton % size == 0 && run_end[p] - p >= size) break;
        }
        out.push_back({v[p].morton, level, v[p].material});
        p += std::size_t{1} << (dimensions * level);
    }
    return out;
}

Matrix8d subnode_interpolation(const Eigen::Vector3i& origin, int size, int cell_size)
{
    Matrix8d h;
    for (int a = 0; a < 8; ++a) {
        const Eigen::Vector3d corner((origin.x() + size * (a & 1)) / double(cell_size),
                                     (origin.y() + size * ((a >> 1) & 1)) / double(cell_size),
                                     (origin.z() + size * ((a >> 2) & 1)) / double(cell_size));
        for (int b = 0; b < 8; ++b) h(a, b) = hex8_shape(b, corner);
    }
    return h;
}

CondensedElement condense_direct(std::span<const CellVoxel> voxels, int cell_level, const Eigen::Vector3d& voxel_size_m,
                                 std::span<const ElasticMaterial> materials)
{
    const auto base = voxel_matrices(voxel_size_m, materials);
    const int cell_size = 1 << cell_level;
    CondensedElement out;
    for (const SubNode& s : full_subnodes(voxels, cell_level)) {
        const int size = 1 << s.level;
        const Matrix8d h = subnode_interpolation(decode(s.first), size, cell_size);
        // Equations 2 and 3: a full sub-node of level l is the fine element scaled by 2^l.
        const Matrix24d k = static_cast<double>(size) * base[s.material].stiffness;
        const Matrix8d m = static_cast<double>(size) * size * size * base[s.material].mass;
        add_congruence(out.stiffness, h, k);
        out.mass += h.transpose() * m * h;
        ++out.steps;
    }
    return out;
}

CondensedElement condense_recursive(std::span<const CellVoxel> voxels, int cell_level,
                                    const Eigen::Vector3d& voxel_size_m, std::span<const ElasticMaterial> materials)
{
    const auto base = voxel_matrices(voxel_size_m, materials);
    Matrix8d child_to_parent[8];
    for (int o = 0; o < 8; ++o) child_to_parent[o] = subnode_interpolation({o & 1, (o >> 1) & 1, (o >> 2) & 1}, 1, 2);

    CondensedElement out;
    if (cell_level == 0) {
        for (const CellVoxel& v : voxels) {
            out.stiffness += base[v.material].stiffness;
            out.mass += base[v.material].mass;
        }
        return out;
    }
    // Level 0 -> 1: each voxel adds its matrices to its parent node.
    std::map<std::uint64_t, VoxelMatrices> level;
    for (const CellVoxel& v : voxels) {
        auto [it, fresh] = level.try_emplace(v.morton >> 3);
        if (fresh) it->second = {Matrix24d::Zero(), Matrix8d::Zero()};
        const Matrix8d& h = child_to_parent[v.morton & 7];
        add_congruence(it->second.stiffness, h, base[v.material].stiffness);
        it->second.mass += h.transpose() * base[v.material].mass * h;
        ++out.steps;
    }
    // Level l -> l + 1 for l = 1 .. L-1: the node matrices are already in their own units, so
    // the same child-to-parent interpolations apply at every level.
    for (int l = 1; l < cell_level; ++l) {
        std::map<std::uint64_t, VoxelMatrices> parent;
        for (const auto& [code, mats] : level) {
            auto [it, fresh] = parent.try_emplace(code >> 3);
            if (fresh) it->second = {Matrix24d::Zero(), Matrix8d::Zero()};
            const Matrix8d& h = child_to_parent[code & 7];
            add_congruence(it->second.stiffness, h, mats.stiffness);
            it->second.mass += h.transpose() * mats.mass * h;
            ++out.steps;
        }
        level = std::move(parent);
    }
    for (const auto& [code, mats] : level) {
        out.stiffness += mats.stiffness;
        out.mass += mats.mass;
    }
    return out;
}

CondensedElement condense_brute_force(std::span<const CellVoxel> voxels, int cell_level,
                                      const Eigen::Vector3d& voxel_size_m, std::span<const ElasticMaterial> materials)
{
    const auto base = voxel_matrices(voxel_size_m, materials);
    const int cell_size = 1 << cell_level;
    CondensedElement out;
    for (const CellVoxel& v : voxels) {
        const Matrix8d h = subnode_interpolation(decode(v.morton), 1, cell_size);
        add_congruence(out.stiffness, h, base[v.material].stiffness);
        out.mass += h.transpose() * base[v.material].mass * h;
        ++out.steps;
    }
    return out;
}

std::uint64_t recursive_step_count(std::span<const CellVoxel> voxels, int cell_level, int dimensions)
{
    std::uint64_t steps = 0;
    for (int l = 0; l < cell_level; ++l) {
        // Distinct nodes of level l: codes >> 3l, counted over the sorted sequence.
        std::uint64_t previous = ~std::uint64_t{0};
        for (const CellVoxel& v : voxels) {
            const std::uint64_t node = v.morton >> (dimensions * l);
            if (node != previous) ++steps;
            previous = node;
        }
    }
    return steps;
}

} // namespace vox::grid
