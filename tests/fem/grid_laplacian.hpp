#pragma once
// A test matrix for sparse factors: the 7-point Laplacian on an n^3 grid of nodes (Neumann
// boundaries) with `block` identical dofs per node (3: isotropic, so turning a node leaves it
// unchanged), plus `shift` times the identity: symmetric positive definite for shift > 0,
// singular (constants in its null space) for shift = 0.

#include <Eigen/SparseCore>

#include <tuple>
#include <vector>

namespace vox::test {

template <int Options = Eigen::ColMajor>
Eigen::SparseMatrix<double, Options> grid_laplacian(int n, double shift, int block = 1)
{
    std::vector<Eigen::Triplet<double>> t;
    auto id = [n](int i, int j, int k) { return (i * n + j) * n + k; };
    auto inside = [n](int i, int j, int k) { return i >= 0 && j >= 0 && k >= 0 && i < n && j < n && k < n; };
    for (int i = 0; i < n; ++i)
        for (int j = 0; j < n; ++j)
            for (int k = 0; k < n; ++k) {
                double degree = 0.0;
                for (const auto& [di, dj, dk] : {std::tuple{1, 0, 0}, std::tuple{-1, 0, 0}, std::tuple{0, 1, 0}, std::tuple{0, -1, 0},
                                                 std::tuple{0, 0, 1}, std::tuple{0, 0, -1}})
                    if (inside(i + di, j + dj, k + dk)) {
                        for (int a = 0; a < block; ++a) t.emplace_back(block * id(i, j, k) + a, block * id(i + di, j + dj, k + dk) + a, -1.0);
                        degree += 1.0;
                    }
                for (int a = 0; a < block; ++a) t.emplace_back(block * id(i, j, k) + a, block * id(i, j, k) + a, degree + shift);
            }
    Eigen::SparseMatrix<double, Options> m(block * n * n * n, block * n * n * n);
    m.setFromTriplets(t.begin(), t.end());
    m.makeCompressed();
    return m;
}

} // namespace vox::test
